//! Where the control socket lives when the configuration says `socket = "auto"`,
//! resolved the same way by `snaked` and `snakectl`.
use std::path::PathBuf;

const FILE: &str = "snaked.sock";
/// The system service's socket (systemd's RuntimeDirectory=snaked).
pub const SYSTEM_SOCKET: &str = "/run/snaked/snaked.sock";

fn euid() -> u32 {
    // SAFETY: geteuid has no preconditions and cannot fail.
    unsafe { libc::geteuid() }
}

fn user_dir() -> PathBuf {
    match std::env::var_os("XDG_RUNTIME_DIR") {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => PathBuf::from(format!("/tmp/snaked-{}", euid())),
    }
}

/// The daemon's socket for `socket = "auto"`: systemd's runtime directory when run as a
/// service, /run/snaked for root, else the user's runtime directory.
pub fn daemon_socket() -> PathBuf {
    if let Some(d) = std::env::var_os("RUNTIME_DIRECTORY").filter(|d| !d.is_empty()) {
        // systemd may list several directories separated by ':'; the first is ours.
        let first = d
            .to_string_lossy()
            .split(':')
            .next()
            .unwrap_or_default()
            .to_owned();
        return PathBuf::from(first).join(FILE);
    }
    if euid() == 0 {
        PathBuf::from(SYSTEM_SOCKET)
    } else {
        user_dir().join(FILE)
    }
}

/// The socket `snakectl` talks to without `--socket`: `$SNAKED_SOCKET`, else the first
/// of the system socket and the user's socket that exists, else the one this user's
/// daemon would create.
pub fn client_socket() -> PathBuf {
    if let Some(p) = std::env::var_os("SNAKED_SOCKET").filter(|p| !p.is_empty()) {
        return PathBuf::from(p);
    }
    let candidates = [PathBuf::from(SYSTEM_SOCKET), user_dir().join(FILE)];
    candidates
        .iter()
        .find(|p| p.exists())
        .cloned()
        .unwrap_or_else(daemon_socket)
}
