//! A headless stand-in for Foxglove: connects to a live view (`snaked --foxglove`),
//! subscribes to every advertised channel and, after SECONDS, prints the messages
//! received per topic and their rate. With SLOW_MS it is a viewer that cannot keep up:
//! it sleeps that long after each message it reads. Used by `scripts/record-timing.sh`
//! and `scripts/live-load.sh` to measure the loop with viewers connected.
//!
//!     cargo run --release --example foxglove_viewer -- ws://127.0.0.1:8765 60 [SLOW_MS]
use std::collections::BTreeMap;
use std::net::TcpStream;
use std::time::{Duration, Instant};

use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

fn main() {
    let mut args = std::env::args().skip(1);
    let url = args.next().unwrap_or_else(|| "ws://127.0.0.1:8765".into());
    let secs: f64 = args.next().map_or(10.0, |s| s.parse().expect("SECONDS"));
    let slow = Duration::from_millis(args.next().map_or(0, |s| s.parse().expect("SLOW_MS")));
    let mut req = url.as_str().into_client_request().expect("a ws:// URL");
    req.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        "foxglove.sdk.v1".parse().expect("header"),
    );
    let (mut ws, _) = connect_retrying(req);
    if let MaybeTlsStream::Plain(s) = ws.get_ref() {
        s.set_read_timeout(Some(Duration::from_millis(100)))
            .expect("read timeout");
    }
    let (mut names, mut counts) = (BTreeMap::new(), BTreeMap::<String, u64>::new());
    let start = Instant::now();
    let mut next_sub = 1u64;
    while start.elapsed().as_secs_f64() < secs {
        let msg = match ws.read() {
            Ok(m) => m,
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                continue;
            }
            Err(e) => {
                // A slow viewer may be cut off by the server: that is what it measures.
                println!(
                    "connection ended after {:.1} s: {e}",
                    start.elapsed().as_secs_f64()
                );
                break;
            }
        };
        if !slow.is_zero() {
            std::thread::sleep(slow);
        }
        match msg {
            Message::Text(t) => {
                let v: serde_json::Value = serde_json::from_str(&t).expect("JSON");
                if v["op"] != "advertise" {
                    continue;
                }
                let mut subs = Vec::new();
                for c in v["channels"].as_array().into_iter().flatten() {
                    let (id, topic) = (c["id"].as_u64().unwrap(), c["topic"].as_str().unwrap());
                    names.insert(next_sub, topic.to_owned());
                    subs.push(serde_json::json!({"id": next_sub, "channelId": id}));
                    next_sub += 1;
                }
                let sub = serde_json::json!({"op": "subscribe", "subscriptions": subs});
                ws.send(Message::Text(sub.to_string().into()))
                    .expect("subscribe");
            }
            // Binary message data: opcode 1, subscription id (u32 LE), time, payload.
            Message::Binary(b) if b.first() == Some(&1) && b.len() >= 5 => {
                let sub = u32::from_le_bytes([b[1], b[2], b[3], b[4]]) as u64;
                if let Some(topic) = names.get(&sub) {
                    *counts.entry(topic.clone()).or_default() += 1;
                }
            }
            _ => {}
        }
    }
    let t = start.elapsed().as_secs_f64();
    for (topic, n) in &counts {
        println!("{topic:24} {n:>9} messages  {:>8.1} /s", *n as f64 / t);
    }
}

fn connect_retrying(
    req: tungstenite::handshake::client::Request,
) -> (
    WebSocket<MaybeTlsStream<TcpStream>>,
    tungstenite::handshake::client::Response,
) {
    let deadline = Instant::now() + Duration::from_secs(20);
    loop {
        match tungstenite::connect(req.clone()) {
            Ok(c) => return c,
            Err(e) if Instant::now() < deadline => {
                eprintln!("waiting for the live view: {e}");
                std::thread::sleep(Duration::from_millis(500));
            }
            Err(e) => panic!("cannot connect: {e}"),
        }
    }
}
