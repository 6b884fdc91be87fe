//! The daemon's TOML configuration (`Config::parse`: the keys, their ranges, the checks
//! between keys, each gait's parameters and controller). Properties: nothing panics;
//! every refusal names the file and the key (or, from the TOML reader, the line);
//! what passes also passes the checks the daemon makes when it starts.
#![no_main]
use std::path::Path;

use libfuzzer_sys::fuzz_target;
use snaked::daemon::config::{Config, ConfigFileError};

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    // `emulator.world` names a file that is read: keep to the repository's files.
    if text.contains("/dev") || text.contains("/proc") || text.contains("/sys") {
        return;
    }
    let path = Path::new("fuzz.toml");
    let cfg = match Config::parse(text, path) {
        Ok(cfg) => cfg,
        Err(e) => return check_error(&e),
    };
    let table = cfg.gait_table(path).expect("checked by parse");
    if let Err((gait, e)) = table.validate_for(cfg.body.module_length_m) {
        panic!(
            "passed the checks, refused at start-up: {}: {e}",
            gait.name()
        );
    }
});

fn check_error(e: &ConfigFileError) {
    let msg = e.to_string();
    assert!(msg.starts_with("fuzz.toml: "), "{msg}");
    match e {
        ConfigFileError::Read { .. } => panic!("read nothing: {msg}"),
        ConfigFileError::Parse { message, .. } => {
            assert!(message.contains("at line "), "no place: {msg}")
        }
        ConfigFileError::Invalid { key, .. } => assert!(msg.contains(key), "{msg}"),
        ConfigFileError::GaitParams { gait, .. } => {
            assert!(msg.contains(&format!("[gait.params.{gait}]")), "{msg}")
        }
        ConfigFileError::Controller { gait, source, .. } => {
            assert!(msg.contains(&format!("[gait.controllers.{gait}]")), "{msg}");
            use snaked::controller_interface::ConfigError as C;
            if let C::Field { path: f, .. }
            | C::OutOfRange { field: f, .. }
            | C::Invalid { field: f, .. } = source
            {
                assert!(!f.is_empty(), "{msg}");
            }
        }
    }
}
