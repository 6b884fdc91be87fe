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

/// Installs the global subscriber: `RUST_LOG` if set, else `default` (e.g. "info"), for
/// what is written; the slow-viewer layer (`live::viewers`) sees the `foxglove`
/// server's lines whatever the level.
pub fn init(default: &str) {
    use tracing_subscriber::Layer;
    use tracing_subscriber::layer::SubscriberExt;
    use tracing_subscriber::util::SubscriberInitExt;
    // RustDDS (the ROS 2 node) logs its discovery's routine at info: warnings only, and
    // none for each datagram past 1500 bytes (a warning per batched sample at 1 kHz);
    // ros2-client warns at every start that ROS_DISTRO is not set (no ROS is needed).
    let filter = EnvFilter::try_from_default_env().unwrap_or_else(|_| {
        EnvFilter::new(format!(
            "{default},rustdds=warn,ros2_client=warn,ros2_client::distributions=error,rustdds::network::udp_sender=error"
        ))
    });
    let style = LogStyle::detect();
    let fmt = tracing_subscriber::fmt::layer()
        .with_writer(std::io::stderr)
        .with_ansi(style.ansi);
    let fmt = if style.timestamps {
        fmt.boxed()
    } else {
        fmt.without_time().boxed()
    };
    let viewers = crate::live::viewers::SlowViewerLayer.with_filter(
        tracing_subscriber::filter::Targets::new().with_target("foxglove", tracing::Level::INFO),
    );
    let _ = tracing_subscriber::registry()
        .with(fmt.with_filter(filter))
        .with(viewers)
        .try_init();
}
