use std::io::{BufRead, BufReader, Write};
use std::os::unix::net::UnixListener;

use serde_json::{Value, json};

use super::*;

/// A server that answers one connection with `script(request) -> lines`, then closes.
fn scripted(script: impl FnOnce(Value) -> Vec<String> + Send + 'static) -> (Endpoint, Guard) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.sock");
    let listener = UnixListener::bind(&path).unwrap();
    let thread = std::thread::spawn(move || {
        let (s, _) = listener.accept().unwrap();
        let mut lines = BufReader::new(s.try_clone().unwrap()).lines();
        let request: Value = serde_json::from_str(&lines.next().unwrap().unwrap()).unwrap();
        let mut w = s;
        for line in script(request) {
            w.write_all(line.as_bytes()).unwrap();
            w.write_all(b"\n").unwrap();
        }
    });
    (Endpoint::Unix(path), Guard(dir, Some(thread)))
}

/// Keeps the socket's directory until the scripted server is done.
struct Guard(
    #[allow(dead_code)] tempfile::TempDir,
    Option<std::thread::JoinHandle<()>>,
);

impl Drop for Guard {
    fn drop(&mut self) {
        if let Some(t) = self.1.take() {
            t.join().unwrap();
        }
    }
}

const OVER_LIMIT: &str = r#"{"id":null,"error":{"code":-32004,"message":"too many clients (at most 2): this connection serves one of estop, limp, hold and closes"}}"#;

fn connect(e: &Endpoint) -> Client {
    Client::connect(e, Some(Duration::from_secs(10))).unwrap()
}

/// Issue 25: over the client limit the server greets with a null-id -32004 before it
/// answers the stop; the greeting is a notice, not the answer.
#[test]
fn the_over_limit_greeting_is_a_notice_and_the_answer_follows() {
    let (e, _g) = scripted(|req| {
        assert_eq!(req["method"], "estop");
        vec![
            OVER_LIMIT.to_owned(),
            json!({"id": req["id"], "result": {"ok": true}}).to_string(),
        ]
    });
    let mut c = connect(&e);
    assert_eq!(c.call("estop", None).unwrap(), json!({"ok": true}));
    assert_eq!(c.notices().len(), 1);
    assert_eq!(c.notices()[0].code, code::TOO_MANY_CLIENTS);
    assert!(c.notices()[0].message.contains("estop"));
}

/// Over every limit the server says why and closes: the call fails as closed, the
/// notice kept to say why.
#[test]
fn a_notice_then_the_close_is_closed_with_the_notice_kept() {
    let (e, _g) = scripted(|_| vec![OVER_LIMIT.to_owned()]);
    let mut c = connect(&e);
    assert!(matches!(c.call("estop", None), Err(ClientError::Closed)));
    assert_eq!(c.notices().len(), 1);
}

/// A null id with another code answers our request (the server could not read its
/// id, e.g. a line too long): the daemon's error, not a protocol failure.
#[test]
fn a_null_id_error_of_another_code_is_the_answer() {
    let (e, _g) = scripted(|_| {
        vec![r#"{"id":null,"error":{"code":-32003,"message":"line too long"}}"#.to_owned()]
    });
    let mut c = connect(&e);
    match c.call("ping", None) {
        Err(ClientError::Rpc(r)) => assert_eq!(r.code, code::LINE_TOO_LONG),
        other => panic!("{other:?}"),
    }
    assert!(c.notices().is_empty());
}
