//! Binding, replacing stale sockets, refusing live ones, TCP, client limit, shutdown.
use crate::support::socket;

use std::os::unix::fs::PermissionsExt;
use std::time::{Duration, Instant};

use snaked::socket::api::code;
use snaked::socket::client::{Client, ClientError, Endpoint};
use snaked::socket::{ServerConfig, ServerError};
use socket::{Harness, LoopSpec, error_code, fake_loop, serve_real_loop};

fn connect(path: &std::path::Path) -> Client {
    Client::connect(
        &Endpoint::Unix(path.to_owned()),
        Some(Duration::from_secs(10)),
    )
    .unwrap()
}

/// TCP listens on loopback only and serves nothing before `auth` with the token: a
/// local user without the token can neither read nor act.
#[test]
fn tcp_listener_on_loopback_needs_the_token() {
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: None,
        tcp_port: Some(0),
        ..ServerConfig::default()
    };
    assert!(matches!(
        snaked::socket::start(cfg.clone(), handle),
        Err(ServerError::TcpWithoutToken)
    ));
    let (fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        tcp_token: Some("s3cret-token".into()),
        ..cfg
    };
    let server = snaked::socket::start(cfg, handle).unwrap();
    let addr = server.tcp_addr().unwrap();
    assert!(addr.ip().is_loopback());
    let connect = || {
        Client::connect(
            &Endpoint::Tcp(addr.to_string()),
            Some(Duration::from_secs(10)),
        )
        .unwrap()
    };
    let mut c = connect();
    for method in ["status", "estop", "gait.list"] {
        let e = c.call(method, None).unwrap_err().to_string();
        assert!(e.contains("-32005") && e.contains("auth"), "{method}: {e}");
    }
    let e = c
        .call("auth", Some(serde_json::json!({"token": "guess"})))
        .unwrap_err()
        .to_string();
    assert!(e.contains("wrong token"), "{e}");
    assert!(fake.seen().is_empty(), "nothing reached the loop");
    c.call("auth", Some(serde_json::json!({"token": "s3cret-token"})))
        .unwrap();
    assert_eq!(c.call("status", None).unwrap()["modules"], 8);
    assert_eq!(c.call("estop", None).unwrap()["ok"], true);
    // Per connection: a new one starts unauthorised.
    let e = connect().call("status", None).unwrap_err().to_string();
    assert!(e.contains("-32005"), "{e}");
    server.shutdown();
}

#[test]
fn stale_socket_file_is_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("snaked.sock");
    // A socket file nobody listens on, as a crashed daemon leaves behind.
    drop(std::os::unix::net::UnixListener::bind(&path).unwrap());
    assert!(path.exists());
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: Some(path.clone()),
        ..ServerConfig::default()
    };
    let server = snaked::socket::start(cfg, handle).expect("stale socket replaced");
    assert_eq!(connect(&path).call("ping", None).unwrap()["pong"], true);
    server.shutdown();
}

#[test]
fn a_live_socket_is_refused_and_keeps_serving() {
    let h = Harness::default_server();
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: Some(h.path.clone()),
        ..ServerConfig::default()
    };
    match snaked::socket::start(cfg, handle) {
        Err(e @ ServerError::InUse { .. }) => {
            assert!(e.to_string().contains(&h.path.display().to_string()), "{e}");
        }
        Err(e) => panic!("expected InUse, got {e}"),
        Ok(_) => panic!("a second server bound a live socket"),
    }
    assert_eq!(h.client().call("ping", None).unwrap()["pong"], true);
}

#[test]
fn a_regular_file_is_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("snaked.sock");
    std::fs::write(&path, "precious").unwrap();
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: Some(path.clone()),
        ..ServerConfig::default()
    };
    assert!(matches!(
        snaked::socket::start(cfg, handle),
        Err(ServerError::NotASocket { .. })
    ));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "precious");
}

#[test]
fn missing_directories_are_created_and_the_mode_is_set() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run/snaked/ctl.sock");
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: Some(path.clone()),
        socket_mode: 0o600,
        ..ServerConfig::default()
    };
    let server = snaked::socket::start(cfg, handle).unwrap();
    let mode = std::fs::metadata(&path).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o600);
    assert_eq!(server.unix_path(), Some(path.as_path()));
    server.shutdown();
}

#[test]
fn an_unusable_path_is_a_clear_error_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let blocker = dir.path().join("not-a-dir");
    std::fs::write(&blocker, "").unwrap();
    let path = blocker.join("snaked.sock");
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: Some(path.clone()),
        ..ServerConfig::default()
    };
    let e = snaked::socket::start(cfg, handle)
        .err()
        .expect("cannot bind there");
    let msg = e.to_string();
    assert!(msg.contains(&path.display().to_string()), "{msg}");
    assert!(msg.contains("directory"), "{msg}");
}

#[test]
fn no_listener_is_an_error() {
    let (_fake, handle) = fake_loop(LoopSpec::default());
    let cfg = ServerConfig {
        unix_path: None,
        tcp_port: None,
        ..ServerConfig::default()
    };
    assert!(matches!(
        snaked::socket::start(cfg, handle),
        Err(ServerError::NoListener)
    ));
}

#[test]
fn shutdown_closes_connections_and_removes_the_socket() {
    let mut h = Harness::default_server();
    let mut c = h.client();
    assert_eq!(c.call("ping", None).unwrap()["pong"], true);
    h.server.take().unwrap().shutdown();
    assert!(!h.path.exists(), "socket file left behind");
    match c.next_message() {
        Err(ClientError::Closed | ClientError::Io(_)) => {}
        other => panic!("connection not closed: {other:?}"),
    }
    assert!(matches!(
        Client::connect(&Endpoint::Unix(h.path.clone()), None),
        Err(ClientError::Connect { .. })
    ));
}

#[test]
fn too_many_clients_are_told_and_closed() {
    let h = Harness::new(LoopSpec::default(), |c| c.max_clients = 2);
    let mut a = h.client();
    let mut b = h.client();
    // Make sure both are being served before the third arrives.
    a.call("ping", None).unwrap();
    b.call("ping", None).unwrap();
    let mut third = h.client();
    let m = third.next_message().unwrap();
    assert_eq!(error_code(&m), code::TOO_MANY_CLIENTS, "{m}");
    assert!(matches!(third.next_message(), Err(ClientError::Closed)));
    // The others are unaffected, and a slot frees when one leaves.
    assert_eq!(a.call("ping", None).unwrap()["pong"], true);
    drop(b);
    let deadline = Instant::now() + Duration::from_secs(10);
    loop {
        let mut c = h.client();
        match c.call("ping", None) {
            Ok(r) => {
                assert_eq!(r["pong"], true);
                break;
            }
            Err(_) if Instant::now() < deadline => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => panic!("slot never freed: {e}"),
        }
    }
}

/// Connections that never send a byte hold every slot: an e-stop still gets through
/// (served over the limit), and once they have idled a newcomer takes a slot from the
/// idlest, which is told why and closed.
#[test]
fn an_estop_gets_through_when_every_slot_is_held() {
    use std::io::{BufRead, BufReader, Write};
    use std::os::unix::net::UnixStream;
    let h = Harness::new(LoopSpec::default(), |c| c.max_clients = 3);
    let squatters: Vec<UnixStream> = (0..3)
        .map(|_| UnixStream::connect(&h.path).unwrap())
        .collect();
    // Let the server admit all three before the stop arrives.
    std::thread::sleep(Duration::from_millis(200));
    let mut stop = UnixStream::connect(&h.path).unwrap();
    stop.set_read_timeout(Some(Duration::from_secs(10)))
        .unwrap();
    stop.write_all(b"{\"id\":9,\"method\":\"estop\"}\n")
        .unwrap();
    let mut lines = BufReader::new(stop).lines();
    let notice: serde_json::Value = serde_json::from_str(&lines.next().unwrap().unwrap()).unwrap();
    assert_eq!(error_code(&notice), code::TOO_MANY_CLIENTS, "{notice}");
    let answer: serde_json::Value = serde_json::from_str(&lines.next().unwrap().unwrap()).unwrap();
    assert_eq!(answer["id"], 9, "{answer}");
    assert_eq!(
        answer["result"]["ok"], true,
        "the e-stop was applied: {answer}"
    );
    assert!(
        h.fake
            .seen()
            .contains(&snaked::rt::messages::LoopRequest::EStop)
    );
    // Over the limit only stops are served.
    let mut other = h.client();
    let refused = other.call("ping", None).unwrap_err().to_string();
    assert!(
        refused.contains("estop") && refused.contains("-32004"),
        "{refused}"
    );

    // After a second of silence the squatters are evictable: a real client gets in.
    std::thread::sleep(Duration::from_millis(1200));
    let mut c = h.client();
    assert_eq!(c.call("ping", None).unwrap()["pong"], true);
    let told: Vec<String> = squatters
        .into_iter()
        .filter_map(|s| {
            s.set_read_timeout(Some(Duration::from_millis(500)))
                .unwrap();
            BufReader::new(s).lines().next().and_then(Result::ok)
        })
        .collect();
    assert_eq!(
        told.len(),
        1,
        "exactly one squatter gave its slot: {told:?}"
    );
    assert!(
        told[0].contains("idle while the client limit was reached"),
        "{told:?}"
    );
}

/// A connection with neither a request nor a telemetry stream is closed after the idle
/// timeout; a subscriber is not.
#[test]
fn idle_connections_time_out_but_subscribers_stay() {
    let h = Harness::new(LoopSpec::default(), |c| {
        c.idle_timeout = Some(Duration::from_millis(300))
    });
    let mut idle = h.client();
    let mut sub = h.client();
    sub.call(
        "telemetry.subscribe",
        Some(serde_json::json!({"rate_hz": 5})),
    )
    .unwrap();
    std::thread::sleep(Duration::from_millis(600));
    let m = idle.next_message().unwrap();
    assert!(
        m["error"]["message"]
            .as_str()
            .unwrap()
            .contains("idle for too long"),
        "{m}"
    );
    assert!(matches!(idle.next_message(), Err(ClientError::Closed)));
    assert_eq!(sub.next_message().unwrap()["method"], "telemetry");
    assert_eq!(sub.call("ping", None).unwrap()["pong"], true);
}

/// A socket directory another user owns, or any user may write without the sticky bit,
/// is refused (another user could swap the socket for an impostor); a directory the
/// daemon creates is its own, mode 0750.
#[test]
fn an_untrusted_socket_directory_is_refused() {
    let start = |dir: &std::path::Path| {
        let (_fake, handle) = fake_loop(LoopSpec::default());
        let cfg = ServerConfig {
            unix_path: Some(dir.join("snaked.sock")),
            ..ServerConfig::default()
        };
        snaked::socket::start(cfg, handle)
    };
    let base = tempfile::tempdir().unwrap();
    let open = base.path().join("open");
    std::fs::create_dir(&open).unwrap();
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o777)).unwrap();
    let e = start(&open).err().expect("world-writable: refused");
    assert!(matches!(e, ServerError::UntrustedDirectory { .. }), "{e}");
    assert!(e.to_string().contains("writable by every user"), "{e}");
    // Sticky, like /tmp: files can only be removed by their owner, so it is fine.
    std::fs::set_permissions(&open, std::fs::Permissions::from_mode(0o1777)).unwrap();
    start(&open).expect("sticky is fine").shutdown();
    // Created by the daemon: its own, 0750.
    let made = base.path().join("made").join("here");
    start(&made).expect("created").shutdown();
    let mode = std::fs::metadata(&made).unwrap().permissions().mode() & 0o777;
    assert_eq!(mode, 0o750);
    // Owned by another user (needs root to arrange; the test runs as root in CI).
    let theirs = base.path().join("theirs");
    std::fs::create_dir(&theirs).unwrap();
    let c = std::ffi::CString::new(theirs.to_str().unwrap()).unwrap();
    // SAFETY: a valid NUL-terminated path; chown has no other preconditions.
    if unsafe { libc::chown(c.as_ptr(), 65534, 65534) } != 0 {
        println!("skipped the other-owner case: chown needs root");
        return;
    }
    let e = start(&theirs).err().expect("another user's: refused");
    assert!(e.to_string().contains("owned by uid 65534"), "{e}");
}

/// Issue 25: with the smallest request queue the configuration accepts
/// (`control.channel_capacity = 8`, the loop's requests per cycle) and the real loop
/// stepped as fast as it runs, a flood of acting requests from many connections gets
/// an answer for every request: applied, busy or refused, never a timeout, and as many
/// "applied" answers as the loop applied. Counted, not timed.
#[test]
fn a_flood_at_the_smallest_queue_answers_every_applied_request() {
    use snaked::bus::echo::EchoBus;
    use snaked::gait::{GaitKind, GaitTable};
    use snaked::rt::harness::{PERIOD_NS, echo_harness_sized};
    use snaked::safety::failsafe::FailsafeConfig;

    const CLIENTS: usize = 24;
    const EACH: usize = 150;
    let capacity = snaked::rt::control_loop::MAX_REQUESTS_PER_CYCLE;
    let h = echo_harness_sized(
        EchoBus::new(8, PERIOD_NS),
        GaitTable::default(),
        GaitKind::Slithering,
        false,
        FailsafeConfig::default(),
        capacity,
    );
    // The loop back to back: acks come as fast as the loop can make them.
    let l = serve_real_loop(h, |control| {
        control.step();
    });
    let path = l.path.clone();
    let flooders: Vec<_> = (0..CLIENTS)
        .map(|_| {
            let mut c = connect(&path);
            std::thread::spawn(move || {
                let mut counts = [0usize; 4]; // applied, busy, refused, timed out
                for _ in 0..EACH {
                    let slot = match c.call("hold", None) {
                        Ok(_) => 0,
                        Err(ClientError::Rpc(e)) if e.code == code::BUSY => 1,
                        Err(ClientError::Rpc(e)) if e.code == code::REFUSED => 2,
                        Err(ClientError::Rpc(e)) if e.code == code::LOOP_TIMEOUT => 3,
                        Err(e) => panic!("{e}"),
                    };
                    counts[slot] += 1;
                    if slot == 1 {
                        // Busy: try again, as a client would, without spinning.
                        std::thread::sleep(Duration::from_millis(1));
                    }
                }
                counts
            })
        })
        .collect();
    let mut total = [0usize; 4];
    for f in flooders {
        for (t, n) in total.iter_mut().zip(f.join().unwrap()) {
            *t += n;
        }
    }
    let applied = connect(&path).call("status", None).unwrap()["requests_applied"]
        .as_u64()
        .unwrap();
    drop(l);
    let [ok, busy, refused, timed_out] = total;
    println!(
        "{ok} applied, {busy} busy, {refused} refused, {timed_out} timed out; \
         the loop applied {applied}"
    );
    assert_eq!(ok + busy + refused + timed_out, CLIENTS * EACH);
    assert_eq!(timed_out, 0, "every request the loop took is answered");
    assert_eq!(ok as u64, applied, "every applied request was told so");
}
