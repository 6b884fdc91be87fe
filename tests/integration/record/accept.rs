//! The live view's server keeps accepting after a failed accept (issue 44: the foxglove
//! crate's accept loop ended on the first error, EMFILE after ~1,000 idle connections,
//! and no client was ever accepted again). The server runs without caps (the library's
//! default; the daemon's caps keep it below its file limit) in a child process that may
//! open 64 files: idle connections run it out of files, the failed accepts are logged
//! and retried, and once they close a new client is served.
use crate::support::record_fixture::{catalog, info};
use crate::support::rig::{Proc, limit_files, raise_file_limit, wait_log};

use std::net::{SocketAddr, TcpStream};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use snaked::live::LiveOptions;
use snaked::record::{RecordOptions, start};
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

/// Set in the child: where it writes the port it listens on.
const CHILD: &str = "SNAKED_TEST_LIVE_ACCEPT_CHILD";
const FILES: u64 = 64;
const FLOOD: usize = 1000;

/// The server side, run by the test below in a child process (the test binary again,
/// this test alone); without the variable it returns at once.
#[test]
#[ignore = "the server side of the test below, run in a child process"]
fn live_view_in_a_child() {
    let Ok(port_file) = std::env::var(CHILD) else {
        return;
    };
    snaked::daemon::logging::init("warn");
    let (catalog, _) = catalog();
    let opts = RecordOptions {
        live: Some(LiveOptions {
            addr: "127.0.0.1:0".parse().expect("addr"),
            ..LiveOptions::default()
        }),
        ..RecordOptions::default()
    };
    let (_tx, rec) = start(opts, info(catalog, false)).expect("start");
    let port = rec.live_addr().expect("a live address").port();
    let tmp = format!("{port_file}.tmp");
    std::fs::write(&tmp, port.to_string()).unwrap();
    std::fs::rename(&tmp, &port_file).unwrap();
    // Serves until the parent closes its stdin.
    let _ = std::io::Read::read_to_end(&mut std::io::stdin(), &mut Vec::new());
}

/// A WebSocket client's first message from the server at `addr` (retrying until one
/// comes, at most 30 s).
fn first_message(addr: SocketAddr) -> String {
    let deadline = Instant::now() + Duration::from_secs(30);
    loop {
        let mut req = format!("ws://{addr}")
            .into_client_request()
            .expect("request");
        req.headers_mut().insert(
            "Sec-WebSocket-Protocol",
            "foxglove.sdk.v1".parse().expect("header"),
        );
        let stream = TcpStream::connect_timeout(&addr, Duration::from_secs(5));
        let served = stream.map_err(|e| e.to_string()).and_then(|s| {
            s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
            let (mut ws, _): (WebSocket<_>, _) =
                tungstenite::client(req, MaybeTlsStream::Plain(s)).map_err(|e| e.to_string())?;
            match ws.read() {
                Ok(Message::Text(t)) => Ok(t.to_string()),
                other => Err(format!("{other:?}")),
            }
        });
        match served {
            Ok(t) => return t,
            Err(e) => assert!(Instant::now() < deadline, "no client served: {e}"),
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

#[test]
fn accept_errors_are_retried_and_a_client_is_served_after_the_flood() {
    raise_file_limit();
    let dir = tempfile::tempdir().unwrap();
    let port_file = dir.path().join("port");
    let log = dir.path().join("log");
    let mut cmd = Command::new(std::env::current_exe().expect("the test binary"));
    cmd.args([
        "record::accept::live_view_in_a_child",
        "--exact",
        "--ignored",
        "--nocapture",
        "--test-threads",
        "1",
    ])
    .env(CHILD, &port_file)
    .env("RUST_LOG", "warn")
    .stdin(Stdio::piped())
    .stdout(Stdio::null())
    .stderr(std::fs::File::create(&log).unwrap());
    limit_files(&mut cmd, FILES);
    let mut child = Proc {
        name: "the live view's child",
        child: Some(cmd.spawn().expect("spawn the child")),
    };
    let deadline = Instant::now() + Duration::from_secs(60);
    let port: u16 = loop {
        if let Ok(p) = std::fs::read_to_string(&port_file) {
            break p.trim().parse().expect("a port");
        }
        assert!(
            child.is_running(),
            "the child exited: {:?}",
            std::fs::read_to_string(&log)
        );
        assert!(Instant::now() < deadline, "the child never listened");
        std::thread::sleep(Duration::from_millis(50));
    };
    let addr = SocketAddr::from(([127, 0, 0, 1], port));
    // Until the listen queue (128) is full too: the server accepts no more.
    let flood: Vec<TcpStream> = (0..FLOOD)
        .map_while(|_| TcpStream::connect_timeout(&addr, Duration::from_secs(1)).ok())
        .collect();
    let text = wait_log(
        &log,
        &["Failed to accept a connection", "Too many open files"],
    );
    let fds = std::fs::read_dir(format!("/proc/{}/fd", child.pid()))
        .map(|d| d.count())
        .unwrap_or(0);
    eprintln!(
        "accept: {} idle connections (until the listen queue was full) against a \
         {FILES}-file limit; the server held {fds} files; its failed accepts logged {} \
         time(s) (at most one every 10 s) and retried",
        flood.len(),
        text.matches("Failed to accept").count()
    );
    assert!(
        flood.len() > FILES as usize,
        "the flood passed the file limit"
    );
    drop(flood);
    let first = first_message(addr);
    assert!(first.contains("serverInfo"), "{first}");
    drop(child.child.as_mut().expect("running").stdin.take());
    assert!(child.wait(Duration::from_secs(30)).success());
}
