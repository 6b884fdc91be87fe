//! The daemon's open files. It raises its soft RLIMIT_NOFILE to the hard limit when it
//! starts (systemd's `LimitNOFILE=` sets both), and the configuration's check refuses
//! connection caps that, with a reserve for everything else the daemon opens, do not fit
//! below that limit: past it, accepting a connection fails (EMFILE) and so does opening
//! anything else.
use std::path::Path;

use super::config::{Config, ConfigFileError};

/// Files the daemon holds besides the connections it caps: the standard streams, the
/// listeners, the tokio runtimes' descriptors, the bus's or the emulator's sockets, the
/// recording, the files it reads, and the control socket's connections served over
/// `control.max_clients` for one stop request (at most 16). 19 are open while it runs
/// with the emulator, a recording and the live view, operating (`/proc/PID/fd`).
pub const RESERVE: u64 = 64;

/// RLIMIT_NOFILE: the open files the process may hold (soft), and what an unprivileged
/// process may raise that to (hard).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileLimit {
    pub soft: u64,
    pub hard: u64,
}

pub fn file_limit() -> std::io::Result<FileLimit> {
    let mut r = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit writes the struct it is given.
    if unsafe { libc::getrlimit(libc::RLIMIT_NOFILE, &mut r) } != 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(FileLimit {
        soft: r.rlim_cur,
        hard: r.rlim_max,
    })
}

/// Raises the soft limit to the hard one (always allowed); the limit now in force.
pub fn raise_file_limit() -> std::io::Result<u64> {
    let l = file_limit()?;
    if l.soft < l.hard {
        let r = libc::rlimit {
            rlim_cur: l.hard,
            rlim_max: l.hard,
        };
        // SAFETY: setrlimit reads the struct it is given.
        if unsafe { libc::setrlimit(libc::RLIMIT_NOFILE, &r) } != 0 {
            return Err(std::io::Error::last_os_error());
        }
    }
    Ok(file_limit()?.soft)
}

impl Config {
    /// The open files the configuration may need at once: the connections it lets in
    /// (each cap, plus the one accepted past it to be closed) and [`RESERVE`].
    pub fn files_needed(&self) -> u64 {
        let fox = &self.foxglove;
        let live = if fox.enabled {
            fox.max_connections as u64 + 1
        } else {
            0
        };
        let control = self.control.max_clients as u64 + 1;
        live + control + RESERVE
    }

    /// Refuses caps that do not fit below `limit` open files.
    pub(super) fn check_file_limit(&self, path: &Path, limit: u64) -> Result<(), ConfigFileError> {
        let needed = self.files_needed();
        if needed <= limit {
            return Ok(());
        }
        let fox = &self.foxglove;
        let (key, value) = if fox.enabled {
            ("foxglove.max_connections", fox.max_connections)
        } else {
            ("control.max_clients", self.control.max_clients)
        };
        let live = if fox.enabled {
            format!("foxglove.max_connections ({}) + 1, ", fox.max_connections)
        } else {
            String::new()
        };
        Err(ConfigFileError::Invalid {
            path: path.to_owned(),
            key,
            value: value.to_string(),
            why: format!(
                "the connections it lets in need {needed} open files at once ({live}\
                 control.max_clients ({}) + 1, and {RESERVE} for the rest of the daemon), \
                 more than the {limit} the process may open (RLIMIT_NOFILE's hard limit; \
                 systemd: LimitNOFILE=): lower the caps or raise the limit",
                self.control.max_clients
            ),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn caps_that_do_not_fit_below_the_file_limit_are_refused() {
        let mut cfg = Config::default();
        cfg.foxglove.enabled = true;
        let p = Path::new("c.toml");
        let needed = cfg.files_needed();
        assert_eq!(needed, 32 + 1 + 64 + 1 + RESERVE);
        assert!(cfg.check_file_limit(p, needed).is_ok());
        let e = cfg.check_file_limit(p, needed - 1).unwrap_err().to_string();
        assert!(
            e.contains("foxglove.max_connections") && e.contains("LimitNOFILE"),
            "{e}"
        );
        cfg.foxglove.enabled = false;
        let e = cfg.check_file_limit(p, 100).unwrap_err().to_string();
        assert!(e.contains("control.max_clients"), "{e}");
    }

    #[test]
    fn the_soft_limit_is_raised_to_the_hard_one() {
        let before = file_limit().unwrap();
        // Raising to the hard limit is what every process may do; the test process keeps it.
        assert_eq!(raise_file_limit().unwrap(), before.hard);
        assert_eq!(file_limit().unwrap().soft, before.hard);
    }
}
