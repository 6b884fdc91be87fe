//! The live view: a WebSocket client (tungstenite, subprotocol `foxglove.sdk.v1`, which
//! the foxglove SDK speaks; the older `foxglove.websocket.v1` name is not offered by
//! the SDK) connects, sees every channel advertised, subscribes, and receives the
//! pushed cycles and the latched world. Counts are checked loosely; no latency is
//! asserted.

use crate::support::record_fixture as fixture;

use std::collections::BTreeMap;
use std::net::TcpStream;
use std::time::{Duration, Instant};

use fixture::*;
use snaked::live::LiveOptions;
use snaked::record::{RecordOptions, Topic, start};
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

const SUBPROTOCOL: &str = "foxglove.sdk.v1";
/// How long the test waits at most for what it expects (not a latency bound).
const PATIENCE: Duration = Duration::from_secs(60);

type Ws = WebSocket<MaybeTlsStream<TcpStream>>;

fn connect(addr: std::net::SocketAddr) -> Ws {
    let mut req = format!("ws://{addr}")
        .into_client_request()
        .expect("request");
    req.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        SUBPROTOCOL.parse().expect("header value"),
    );
    let (ws, resp) = tungstenite::connect(req).expect("connect to the live view");
    assert_eq!(
        resp.headers()
            .get("sec-websocket-protocol")
            .and_then(|v| v.to_str().ok()),
        Some(SUBPROTOCOL)
    );
    if let MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(Duration::from_millis(200)))
            .expect("read timeout");
    }
    ws
}

/// Reads one message; `None` on a read timeout.
fn read(ws: &mut Ws) -> Option<Message> {
    match ws.read() {
        Ok(m) => Some(m),
        Err(tungstenite::Error::Io(e))
            if matches!(
                e.kind(),
                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
            ) =>
        {
            None
        }
        Err(e) => panic!("live view connection failed: {e}"),
    }
}

/// Reads until every topic is advertised: topic → channel id.
fn advertised(ws: &mut Ws) -> BTreeMap<String, u64> {
    let mut topics = BTreeMap::new();
    let deadline = Instant::now() + PATIENCE;
    while topics.len() < Topic::ALL.len() + 1 && Instant::now() < deadline {
        let Some(Message::Text(t)) = read(ws) else {
            continue;
        };
        let v: serde_json::Value = serde_json::from_str(&t).expect("JSON control message");
        if v["op"] == "advertise" {
            for c in v["channels"].as_array().expect("channels") {
                let topic = c["topic"].as_str().expect("topic").to_owned();
                assert!(c["schemaName"].is_string(), "{topic} has a schema");
                topics.insert(topic, c["id"].as_u64().expect("id"));
            }
        }
    }
    topics
}

/// A MessageData frame: (subscription id, payload).
fn message_data(b: &[u8]) -> Option<(u32, &[u8])> {
    if b.len() < 13 || b[0] != 0x01 {
        return None;
    }
    let sub = u32::from_le_bytes(b[1..5].try_into().ok()?);
    Some((sub, &b[13..]))
}

#[test]
fn a_client_sees_the_channels_and_receives_joints_and_the_latched_world() {
    let (catalog, id) = catalog();
    let opts = RecordOptions {
        live: Some(LiveOptions {
            addr: "127.0.0.1:0".parse().expect("addr"),
            station: None,
            ..LiveOptions::default()
        }),
        ..RecordOptions::default()
    };
    let (tx, rec) = start(opts, info(catalog, true)).expect("start");
    let addr = rec.live_addr().expect("a live address");
    assert_ne!(addr.port(), 0, "the bound port is reported");

    let mut ws = connect(addr);
    let topics = advertised(&mut ws);
    let mut expected: Vec<&str> = Topic::ALL.iter().map(|t| t.name()).collect();
    // The live view's own: slow viewers reported (live::viewers).
    expected.push(snaked::live::viewers::TOPIC);
    assert_eq!(topics.keys().map(String::as_str).collect::<Vec<_>>(), {
        let mut e = expected.clone();
        e.sort_unstable();
        e
    });
    assert_eq!(rec.status().live_clients, 1);

    let (joints_sub, world_sub) = (1u32, 2u32);
    let subscribe = serde_json::json!({"op": "subscribe", "subscriptions": [
        {"id": joints_sub, "channelId": topics["/joints"]},
        {"id": world_sub, "channelId": topics["/scene/world"]},
    ]});
    ws.send(Message::Text(subscribe.to_string().into()))
        .expect("subscribe");
    // The world was published before anyone connected: it comes latched.
    let mut world = 0;
    let mut joints = 0u64;
    let deadline = Instant::now() + PATIENCE;
    while world == 0 && Instant::now() < deadline {
        if let Some(Message::Binary(b)) = read(&mut ws)
            && let Some((sub, _)) = message_data(&b)
        {
            world += u64::from(sub == world_sub);
            joints += u64::from(sub == joints_sub);
        }
    }
    assert_eq!(world, 1, "the latched world arrives once on subscribing");

    // Push 1000 cycles at about 1 kHz from another thread (the loop's side).
    const PUSHED: u64 = 1000;
    let pusher = std::thread::spawn(move || {
        for k in 0..PUSHED {
            tx.push(&cycle(k, id, true));
            if k % 10 == 9 {
                std::thread::sleep(Duration::from_millis(10));
            }
        }
        tx
    });
    let mut first_joints = None;
    let deadline = Instant::now() + PATIENCE;
    while joints < PUSHED / 2 && Instant::now() < deadline {
        if let Some(Message::Binary(b)) = read(&mut ws)
            && let Some((sub, payload)) = message_data(&b)
            && sub == joints_sub
        {
            joints += 1;
            first_joints.get_or_insert_with(|| payload.to_vec());
        }
    }
    let tx = pusher.join().expect("pusher");
    assert!(
        joints >= PUSHED / 2,
        "received {joints} /joints messages of {PUSHED} pushed"
    );
    let v: serde_json::Value =
        serde_json::from_slice(&first_joints.expect("a /joints message")).expect("JSON");
    assert_eq!(v["position_rad"].as_array().map(Vec::len), Some(MODULES));
    let _ = ws.close(None);
    let summary = rec.finish().expect("finish");
    assert_eq!(summary.items + summary.dropped, PUSHED);
    assert_eq!(summary.dropped, tx.dropped());
    assert_eq!(summary.messages_written, 0, "no file was asked for");
}
