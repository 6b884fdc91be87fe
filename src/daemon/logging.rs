//! Log output of the binaries: to stderr, with colour only on a terminal, and in the
//! journal's own style under systemd (no colour, no timestamp: journald adds its own).

use std::io::IsTerminal;

use tracing_subscriber::EnvFilter;

/// How the logs are written, decided from where stderr goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LogStyle {
    pub ansi: bool,
    pub timestamps: bool,
}

impl LogStyle {
    /// Colour only on a terminal; under systemd (`JOURNAL_STREAM` set, as the service
    /// manager does for a unit's stdout/stderr) neither colour nor timestamps.
    pub fn detect() -> Self {
        let journal = std::env::var_os("JOURNAL_STREAM").is_some();
        Self {
            ansi: std::io::stderr().is_terminal() && !journal,
            timestamps: !journal,
        }
    }
}

/// Installs the global subscriber: `RUST_LOG` if set, else `default` (e.g. "info").
pub fn init(default: &str) {
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| EnvFilter::new(default));
    let style = LogStyle::detect();
    let builder = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(style.ansi);
    if style.timestamps {
        builder.init();
    } else {
        builder.without_time().init();
    }
}
