//! A viewer that cannot keep up.
use super::daemon;
use crate::support::foxglove_ws::FoxgloveClient;

use std::time::Duration;

#[test]
fn a_viewer_that_cannot_keep_up_is_thinned_and_reported() {
    let d = daemon("");
    let mut slow = FoxgloveClient::connect(d.fox, Duration::from_secs(30));
    slow.drain(Duration::from_millis(500));
    slow.subscribe_all();
    // It never reads again: once the socket's buffers and its outbox are full, the
    // server drops its oldest messages, and every viewer is told.
    let mut watcher = FoxgloveClient::connect(d.fox, Duration::from_secs(10));
    assert!(
        watcher.wait_status_message("cannot keep up", Duration::from_secs(30)),
        "statuses seen: {:?}",
        watcher.statuses
    );
    let reports = d.stop_with(&["/live/viewers"]).remove(0);
    assert!(
        reports.iter().any(|r| r["event"] == "thinned"),
        "{reports:?}"
    );
    drop(slow);
}
