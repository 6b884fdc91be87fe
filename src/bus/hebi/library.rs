//! Finding and loading HEBI's C library (`libhebi`) at run time. It is never built in
//! or shipped (HEBI ships no licence with it): it comes from the configuration's path,
//! `$SNAKED_LIBHEBI`, an installed `hebi-py` (its `hebi/lib/`), or `target/hebi/`
//! beside the build (`scripts/fetch-libhebi.sh`). Loaded once per process and never
//! unloaded: its threads run until the process ends.

use std::ffi::CStr;
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use super::ffi::{Functions, Metadata, field};

/// The library as loaded: its functions, version and message layouts.
pub struct Api {
    pub f: Functions,
    pub command: Metadata,
    pub feedback: Metadata,
    pub version: (i32, i32, i32),
    pub path: PathBuf,
}

#[derive(Debug, thiserror::Error)]
pub enum LibraryError {
    #[error(
        "libhebi not found; looked in: {}. Set hebi.library in the configuration or \
         $SNAKED_LIBHEBI to libhebi.so.2.x, install hebi-py (pip install hebi-py), or run \
         scripts/fetch-libhebi.sh",
        looked.join(", ")
    )]
    NotFound { looked: Vec<String> },
    #[error("cannot load {path} as libhebi: {why}")]
    Load { path: PathBuf, why: String },
    #[error("{path} is libhebi {found}, which this daemon cannot use: {why}")]
    WrongVersion {
        path: PathBuf,
        found: String,
        why: String,
    },
    #[error("libhebi is already loaded from {loaded}; cannot load {asked} in the same process")]
    Another { loaded: PathBuf, asked: PathBuf },
}

/// Environment variable naming the library when the configuration does not.
pub const ENV: &str = "SNAKED_LIBHEBI";

/// Where the library is: `configured` if given (only there), else `$SNAKED_LIBHEBI`,
/// an installed hebi-py, `target/hebi/` beside this executable's build.
pub fn find(configured: Option<&Path>) -> Result<PathBuf, LibraryError> {
    if let Some(p) = configured {
        return if p.is_file() {
            Ok(p.to_owned())
        } else {
            Err(LibraryError::NotFound {
                looked: vec![format!("{} (hebi.library)", p.display())],
            })
        };
    }
    let mut looked = Vec::new();
    if let Some(p) = std::env::var_os(ENV).filter(|p| !p.is_empty()) {
        let p = PathBuf::from(p);
        if p.is_file() {
            return Ok(p);
        }
        looked.push(format!("{} (${ENV})", p.display()));
    }
    let mut dirs = Vec::new();
    match hebi_py_dir() {
        Some(d) => dirs.push((d.join("lib"), "hebi-py")),
        None => looked.push("an installed hebi-py (python3 finds none)".into()),
    }
    if let Ok(exe) = std::env::current_exe() {
        // target/<profile>/snaked or target/<profile>/deps/<test> → target/hebi
        for up in exe.ancestors().skip(1).take(3) {
            if up.file_name().is_some_and(|n| n == "target") {
                dirs.push((up.join("hebi"), "scripts/fetch-libhebi.sh"));
                break;
            }
        }
    }
    for (dir, what) in dirs {
        if let Some(p) = newest_versioned(&dir) {
            return Ok(p);
        }
        looked.push(format!("{}/libhebi.so.2.*.* ({what})", dir.display()));
    }
    Err(LibraryError::NotFound { looked })
}

/// hebi-py's package folder, asked of python3 without importing the package.
fn hebi_py_dir() -> Option<PathBuf> {
    let out = std::process::Command::new("python3")
        .args([
            "-c",
            "import importlib.util as u; s = u.find_spec('hebi'); \
             print(s.submodule_search_locations[0] if s else '')",
        ])
        .stderr(std::process::Stdio::null())
        .output()
        .ok()?;
    let s = String::from_utf8(out.stdout).ok()?;
    let s = s.trim();
    (!s.is_empty()).then(|| PathBuf::from(s))
}

/// `libhebi.so.2.X.Y` with the highest version in `dir`. The wheel's unversioned
/// names are small text files, not links, so only the fully versioned name counts.
fn newest_versioned(dir: &Path) -> Option<PathBuf> {
    let mut best: Option<((u32, u32), PathBuf)> = None;
    for e in std::fs::read_dir(dir).ok()?.flatten() {
        let name = e.file_name();
        let Some(v) = name.to_str().and_then(|n| n.strip_prefix("libhebi.so.2.")) else {
            continue;
        };
        let mut parts = v.split('.').map(|p| p.parse::<u32>().ok());
        if let (Some(Some(minor)), Some(Some(rev)), None) =
            (parts.next(), parts.next(), parts.next())
            && best.as_ref().is_none_or(|(b, _)| (minor, rev) > *b)
        {
            best = Some(((minor, rev), e.path()));
        }
    }
    best.map(|(_, p)| p)
}

static LOADED: OnceLock<Api> = OnceLock::new();

/// Loads the library at `path` (once per process) and checks that it is a libhebi 2.x
/// whose messages hold every field the bus uses.
pub fn load(path: &Path) -> Result<&'static Api, LibraryError> {
    let canonical = path.canonicalize().unwrap_or_else(|_| path.to_owned());
    if let Some(api) = LOADED.get() {
        return if api.path == canonical {
            Ok(api)
        } else {
            Err(LibraryError::Another {
                loaded: api.path.clone(),
                asked: canonical,
            })
        };
    }
    let api = open(&canonical)?;
    // Two threads racing to load the same path both end with the first one's.
    let _ = LOADED.set(api);
    let api = LOADED.get().expect("set above");
    if api.path != canonical {
        return Err(LibraryError::Another {
            loaded: api.path.clone(),
            asked: canonical,
        });
    }
    Ok(api)
}

fn open(path: &Path) -> Result<Api, LibraryError> {
    let load_err = |why: String| LibraryError::Load {
        path: path.to_owned(),
        why,
    };
    // libloading's error says only "dlopen failed"; the loader's reason is its source.
    // SAFETY: loading runs the library's initialisers; libhebi's are known to be sound.
    let lib = unsafe { libloading::Library::new(path) }.map_err(|e| {
        load_err(match std::error::Error::source(&e) {
            Some(why) => format!("{e}: {why}"),
            None => e.to_string(),
        })
    })?;
    macro_rules! sym {
        ($name:literal) => {
            // SAFETY: the type is hebi.h's declaration of the symbol (ffi.rs).
            *unsafe { lib.get(concat!($name, "\0").as_bytes()) }
                .map_err(|e| load_err(format!("no {} ({e}): not libhebi 2.x", $name)))?
        };
    }
    let f = Functions {
        get_library_version: sym!("hebiGetLibraryVersion"),
        get_last_error: sym!("hebiGetLastError"),
        command_get_metadata: sym!("hebiCommandGetMetadata"),
        feedback_get_metadata: sym!("hebiFeedbackGetMetadata"),
        lookup_create: sym!("hebiLookupCreate"),
        lookup_release: sym!("hebiLookupRelease"),
        create_lookup_entry_list: sym!("hebiCreateLookupEntryList"),
        lookup_entry_list_get_size: sym!("hebiLookupEntryListGetSize"),
        lookup_entry_list_get_name: sym!("hebiLookupEntryListGetName"),
        lookup_entry_list_get_family: sym!("hebiLookupEntryListGetFamily"),
        lookup_entry_list_get_mac_address: sym!("hebiLookupEntryListGetMacAddress"),
        lookup_entry_list_release: sym!("hebiLookupEntryListRelease"),
        group_create_imitation: sym!("hebiGroupCreateImitation"),
        group_create_from_names: sym!("hebiGroupCreateFromNames"),
        group_create_from_family: sym!("hebiGroupCreateFromFamily"),
        group_get_size: sym!("hebiGroupGetSize"),
        group_send_command: sym!("hebiGroupSendCommand"),
        group_send_command_with_acknowledgement: sym!("hebiGroupSendCommandWithAcknowledgement"),
        group_set_command_lifetime: sym!("hebiGroupSetCommandLifetime"),
        group_set_feedback_frequency_hz: sym!("hebiGroupSetFeedbackFrequencyHz"),
        group_register_feedback_handler: sym!("hebiGroupRegisterFeedbackHandler"),
        group_clear_feedback_handlers: sym!("hebiGroupClearFeedbackHandlers"),
        group_release: sym!("hebiGroupRelease"),
        group_command_create: sym!("hebiGroupCommandCreate"),
        group_command_get_module_command: sym!("hebiGroupCommandGetModuleCommand"),
        group_command_clear: sym!("hebiGroupCommandClear"),
        group_command_release: sym!("hebiGroupCommandRelease"),
        group_feedback_get_size: sym!("hebiGroupFeedbackGetSize"),
        group_feedback_get_module_feedback: sym!("hebiGroupFeedbackGetModuleFeedback"),
        command_get_reference: sym!("hebiCommandGetReference"),
        feedback_get_reference: sym!("hebiFeedbackGetReference"),
    };
    let (mut major, mut minor, mut rev) = (0, 0, 0);
    // SAFETY: three valid out-pointers.
    unsafe { (f.get_library_version)(&mut major, &mut minor, &mut rev) };
    let (mut command, mut feedback) = (Metadata::default(), Metadata::default());
    // SAFETY: valid out-pointers to hebi.h's metadata layout.
    unsafe {
        (f.command_get_metadata)(&mut command);
        (f.feedback_get_metadata)(&mut feedback);
    }
    let found = format!("{major}.{minor}.{rev}");
    check(major, &command, &feedback).map_err(|why| LibraryError::WrongVersion {
        path: path.to_owned(),
        found,
        why,
    })?;
    // Never unloaded: the library's lookup and feedback threads outlive any one bus.
    std::mem::forget(lib);
    Ok(Api {
        f,
        command,
        feedback,
        version: (major, minor, rev),
        path: path.to_owned(),
    })
}

/// Number of command float fields the gains use: PositionKp … EffortOutputLowpass.
pub const GAIN_FIELDS: u32 = 39;

/// A libhebi 2.x whose messages hold every field the bus reads and writes (the enums
/// only grow, so a field's index stays valid in later versions).
pub fn check(major: i32, command: &Metadata, feedback: &Metadata) -> Result<(), String> {
    if major != 2 {
        return Err("the bus speaks libhebi's C API 2.x".into());
    }
    let need = [
        (
            "command float",
            command.float_field_count,
            field::CMD_POSITION_KP + GAIN_FIELDS,
        ),
        (
            "command angle",
            command.high_res_angle_field_count,
            field::CMD_POSITION + 1,
        ),
        (
            "command enum",
            command.enum_field_count,
            field::CMD_CONTROL_STRATEGY + 1,
        ),
        (
            "feedback float",
            feedback.float_field_count,
            field::FBK_DEFLECTION + 1,
        ),
        (
            "feedback angle",
            feedback.high_res_angle_field_count,
            field::FBK_POSITION + 1,
        ),
        (
            "feedback uint64",
            feedback.uint64_field_count,
            field::FBK_HARDWARE_TRANSMIT_TIME + 1,
        ),
        (
            "feedback vector",
            feedback.vector3f_field_count,
            field::FBK_GYRO + 1,
        ),
        (
            "feedback quaternion",
            feedback.quaternionf_field_count,
            field::FBK_ORIENTATION + 1,
        ),
        (
            "feedback enum",
            feedback.enum_field_count,
            field::FBK_COMMAND_LIFETIME_STATE + 1,
        ),
    ];
    for (what, has, needs) in need {
        if has < needs {
            return Err(format!(
                "its {what} fields are {has}, the bus needs {needs}"
            ));
        }
    }
    for m in [command, feedback] {
        if m.message_bitfield_count == 0 {
            return Err("its messages report no presence bits".into());
        }
    }
    Ok(())
}

impl Api {
    /// The library's last error on this thread, for messages.
    pub fn last_error(&self) -> String {
        // SAFETY: returns a NUL-terminated string the library owns, or null.
        let p = unsafe { (self.f.get_last_error)() };
        if p.is_null() {
            return "no error text".into();
        }
        // SAFETY: non-null, NUL-terminated, valid until the next call on this thread.
        unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
    }

    pub fn version_string(&self) -> String {
        let (a, b, c) = self.version;
        format!("{a}.{b}.{c}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The counts libhebi 2.27.0 reports (hebi-py 2.16.1's enums agree).
    fn v2_27() -> (Metadata, Metadata) {
        let command = Metadata {
            float_field_count: 61,
            high_res_angle_field_count: 3,
            enum_field_count: 4,
            message_bitfield_count: 150,
            ..Metadata::default()
        };
        let feedback = Metadata {
            float_field_count: 48,
            high_res_angle_field_count: 3,
            vector3f_field_count: 6,
            quaternionf_field_count: 2,
            uint64_field_count: 8,
            enum_field_count: 10,
            message_bitfield_count: 135,
            ..Metadata::default()
        };
        (command, feedback)
    }

    #[test]
    fn another_major_version_or_missing_fields_are_refused_with_the_reason() {
        let (c, f) = v2_27();
        assert_eq!(check(2, &c, &f), Ok(()));
        assert!(check(3, &c, &f).unwrap_err().contains("2.x"));
        let few = Metadata {
            quaternionf_field_count: 0,
            ..f
        };
        let why = check(2, &c, &few).unwrap_err();
        assert!(why.contains("feedback quaternion fields are 0"), "{why}");
        let few = Metadata {
            float_field_count: 40,
            ..c
        };
        let why = check(2, &few, &f).unwrap_err();
        assert!(
            why.contains("command float fields are 40, the bus needs 41"),
            "{why}"
        );
    }

    #[test]
    fn only_fully_versioned_names_count_and_the_newest_wins() {
        let dir = tempfile::tempdir().unwrap();
        for name in [
            "libhebi.so",
            "libhebi.so.2",
            "libhebi.so.2.27",
            "libhebi.so.2.9.1",
        ] {
            std::fs::write(dir.path().join(name), "x").unwrap();
        }
        assert_eq!(
            newest_versioned(dir.path()),
            Some(dir.path().join("libhebi.so.2.9.1"))
        );
        std::fs::write(dir.path().join("libhebi.so.2.27.0"), "x").unwrap();
        assert_eq!(
            newest_versioned(dir.path()),
            Some(dir.path().join("libhebi.so.2.27.0"))
        );
    }

    #[test]
    fn a_configured_path_that_is_missing_names_itself() {
        let e = find(Some(Path::new("/nowhere/libhebi.so.2.27.0"))).unwrap_err();
        assert!(
            e.to_string()
                .contains("/nowhere/libhebi.so.2.27.0 (hebi.library)")
        );
    }
}
