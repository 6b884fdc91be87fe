//! A Foxglove WebSocket client for the tests (tungstenite, subprotocol
//! `foxglove.sdk.v1`): what Foxglove's panels send — service calls (Service Call
//! panel), a client channel and its messages (Teleop panel) — and what they read back.

use std::collections::BTreeMap;
use std::net::{IpAddr, SocketAddr, TcpStream};
use std::time::{Duration, Instant};

use serde_json::{Value, json};
use tungstenite::client::IntoClientRequest;
use tungstenite::stream::MaybeTlsStream;
use tungstenite::{Message, WebSocket};

const SUBPROTOCOL: &str = "foxglove.sdk.v1";

pub struct FoxgloveClient {
    ws: WebSocket<MaybeTlsStream<TcpStream>>,
    /// Service name → id, from `advertiseServices`.
    pub services: BTreeMap<String, u32>,
    /// Status messages the server sent this client.
    pub statuses: Vec<Value>,
    /// Channel id → topic, from `advertise`.
    pub channels: BTreeMap<u64, String>,
    next_call: u32,
}

impl FoxgloveClient {
    /// Connects (retrying until the server listens) and reads the advertisements.
    pub fn connect(addr: SocketAddr, timeout: Duration) -> Self {
        Self::connect_from(addr, None, timeout)
    }

    /// As [`Self::connect`], from the local address `source` (on loopback, 127.0.0.2 is
    /// another client address than 127.0.0.1).
    pub fn connect_from(addr: SocketAddr, source: Option<IpAddr>, timeout: Duration) -> Self {
        let deadline = Instant::now() + timeout;
        let ws = loop {
            let mut req = format!("ws://{addr}")
                .into_client_request()
                .expect("request");
            req.headers_mut().insert(
                "Sec-WebSocket-Protocol",
                SUBPROTOCOL.parse().expect("header"),
            );
            let opened = match source {
                None => TcpStream::connect(addr),
                Some(ip) => tcp_from(ip, addr),
            };
            let handshake = opened.map_err(|e| e.to_string()).and_then(|s| {
                tungstenite::client(req, MaybeTlsStream::Plain(s)).map_err(|e| e.to_string())
            });
            match handshake {
                Ok((ws, _)) => break ws,
                Err(e) => {
                    assert!(Instant::now() < deadline, "connecting to ws://{addr}: {e}");
                    std::thread::sleep(Duration::from_millis(100));
                }
            }
        };
        if let MaybeTlsStream::Plain(s) = ws.get_ref() {
            s.set_read_timeout(Some(Duration::from_millis(100)))
                .expect("timeout");
        }
        let mut c = Self {
            ws,
            services: BTreeMap::new(),
            statuses: Vec::new(),
            channels: BTreeMap::new(),
            next_call: 1,
        };
        let deadline = Instant::now() + Duration::from_secs(10);
        while c.services.is_empty() && Instant::now() < deadline {
            c.read_one();
        }
        c
    }

    /// Reads one message (None on a read timeout); notes services and statuses.
    fn read_one(&mut self) -> Option<Message> {
        let m = match self.ws.read() {
            Ok(m) => m,
            Err(tungstenite::Error::Io(e))
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return None;
            }
            Err(e) => panic!("foxglove connection failed: {e}"),
        };
        if let Message::Text(t) = &m {
            let v: Value = serde_json::from_str(t).expect("JSON control message");
            match v["op"].as_str() {
                Some("advertiseServices") => {
                    for s in v["services"].as_array().expect("services") {
                        let name = s["name"].as_str().expect("name").to_owned();
                        self.services
                            .insert(name, s["id"].as_u64().expect("id") as u32);
                    }
                }
                Some("status") => self.statuses.push(v.clone()),
                Some("advertise") => {
                    for c in v["channels"].as_array().into_iter().flatten() {
                        let (id, topic) = (c["id"].as_u64(), c["topic"].as_str());
                        if let (Some(id), Some(topic)) = (id, topic) {
                            self.channels.insert(id, topic.to_owned());
                        }
                    }
                }
                _ => {}
            }
        }
        Some(m)
    }

    /// Calls service `name` with `params` (JSON): its answer, or the failure's message.
    pub fn call(&mut self, name: &str, params: Value) -> Result<Value, String> {
        let id = *self
            .services
            .get(name)
            .unwrap_or_else(|| panic!("no service {name}"));
        let call = self.next_call;
        self.next_call += 1;
        let payload = params.to_string();
        let mut b = vec![0x02];
        b.extend_from_slice(&id.to_le_bytes());
        b.extend_from_slice(&call.to_le_bytes());
        b.extend_from_slice(&4u32.to_le_bytes());
        b.extend_from_slice(b"json");
        b.extend_from_slice(payload.as_bytes());
        self.ws.send(Message::Binary(b.into())).expect("send call");
        let deadline = Instant::now() + Duration::from_secs(20);
        while Instant::now() < deadline {
            match self.read_one() {
                Some(Message::Binary(b)) if b.first() == Some(&0x03) && b.len() >= 13 => {
                    let got = u32::from_le_bytes(b[5..9].try_into().unwrap());
                    if got != call {
                        continue;
                    }
                    let n = u32::from_le_bytes(b[9..13].try_into().unwrap()) as usize;
                    let v = serde_json::from_slice(&b[13 + n..]).expect("a JSON answer");
                    return Ok(v);
                }
                Some(Message::Text(t)) => {
                    let v: Value = serde_json::from_str(&t).unwrap();
                    if v["op"] == "serviceCallFailure" && v["callId"] == json!(call) {
                        return Err(v["message"].as_str().unwrap_or_default().to_owned());
                    }
                }
                _ => {}
            }
        }
        panic!("no answer to {name}");
    }

    /// Advertises a client channel (as the Teleop panel does).
    pub fn advertise(&mut self, id: u32, topic: &str) {
        self.advertise_in(id, topic, "json");
    }

    /// Advertises a client channel whose messages are in `encoding`.
    pub fn advertise_in(&mut self, id: u32, topic: &str, encoding: &str) {
        let m = json!({"op": "advertise", "channels": [
            {"id": id, "topic": topic, "encoding": encoding, "schemaName": "geometry_msgs/Twist"}
        ]});
        self.ws
            .send(Message::Text(m.to_string().into()))
            .expect("advertise");
    }

    /// Publishes `msg` on client channel `id`.
    pub fn publish(&mut self, id: u32, msg: &Value) {
        let mut b = vec![0x01];
        b.extend_from_slice(&id.to_le_bytes());
        b.extend_from_slice(msg.to_string().as_bytes());
        self.ws.send(Message::Binary(b.into())).expect("publish");
    }

    /// Reads whatever arrives for `d` (statuses are kept).
    pub fn drain(&mut self, d: Duration) {
        let end = Instant::now() + d;
        while Instant::now() < end {
            self.read_one();
        }
    }
}

/// A TCP connection to `addr` from the local address `source`.
pub fn tcp_from(source: IpAddr, addr: SocketAddr) -> std::io::Result<TcpStream> {
    let s = socket2::Socket::new(
        socket2::Domain::for_address(addr),
        socket2::Type::STREAM,
        None,
    )?;
    s.bind(&SocketAddr::new(source, 0).into())?;
    s.connect(&addr.into())?;
    Ok(s.into())
}

/// A twist as the Teleop panel publishes it.
pub fn twist(forward: f64, turn: f64) -> Value {
    json!({"linear": {"x": forward, "y": 0.0, "z": 0.0}, "angular": {"x": 0.0, "y": 0.0, "z": turn}})
}

impl FoxgloveClient {
    /// Sends a parameters request (`getParameters` / `setParameters`) and waits for the
    /// `parameterValues` with its id: name → value.
    fn parameters(&mut self, msg: Value, id: &str) -> BTreeMap<String, Value> {
        self.ws
            .send(Message::Text(msg.to_string().into()))
            .expect("send");
        let deadline = Instant::now() + Duration::from_secs(20);
        while Instant::now() < deadline {
            if let Some(Message::Text(t)) = self.read_one() {
                let v: Value = serde_json::from_str(&t).unwrap();
                if v["op"] == "parameterValues" && v["id"] == id {
                    return v["parameters"]
                        .as_array()
                        .expect("parameters")
                        .iter()
                        .map(|p| (p["name"].as_str().unwrap().to_owned(), p["value"].clone()))
                        .collect();
                }
            }
        }
        panic!("no parameterValues {id}");
    }

    pub fn get_parameters(&mut self, names: &[&str]) -> BTreeMap<String, Value> {
        let id = format!("get{}", self.next_call);
        self.next_call += 1;
        self.parameters(
            json!({"op": "getParameters", "parameterNames": names, "id": id}),
            &id,
        )
    }

    pub fn set_parameters(&mut self, params: &[(&str, Value)]) -> BTreeMap<String, Value> {
        let id = format!("set{}", self.next_call);
        self.next_call += 1;
        let ps: Vec<Value> = params
            .iter()
            .map(|(n, v)| json!({"name": n, "value": v}))
            .collect();
        self.parameters(
            json!({"op": "setParameters", "parameters": ps, "id": id}),
            &id,
        )
    }
}

impl FoxgloveClient {
    /// Fetches asset `uri` (`fetchAsset`): its bytes, or the server's error message.
    pub fn fetch_asset(&mut self, uri: &str) -> Result<Vec<u8>, String> {
        let id = self.next_call;
        self.next_call += 1;
        let m = json!({"op": "fetchAsset", "uri": uri, "requestId": id});
        self.ws
            .send(Message::Text(m.to_string().into()))
            .expect("fetchAsset");
        let deadline = Instant::now() + Duration::from_secs(20);
        while Instant::now() < deadline {
            // FetchAssetResponse: op 4, request id, status (0 ok), error length, error, data.
            if let Some(Message::Binary(b)) = self.read_one()
                && b.first() == Some(&0x04)
                && b.len() >= 10
                && u32::from_le_bytes(b[1..5].try_into().unwrap()) == id
            {
                let n = u32::from_le_bytes(b[6..10].try_into().unwrap()) as usize;
                return match b[5] {
                    0 => Ok(b[10 + n..].to_vec()),
                    _ => Err(String::from_utf8_lossy(&b[10..10 + n]).into_owned()),
                };
            }
        }
        panic!("no answer to fetchAsset {uri}");
    }
}

impl FoxgloveClient {
    /// Subscribes to updates of `names` (as the Parameters panel does).
    pub fn subscribe_parameters(&mut self, names: &[&str]) {
        let m = json!({"op": "subscribeParameterUpdates", "parameterNames": names});
        self.ws
            .send(Message::Text(m.to_string().into()))
            .expect("subscribe");
    }

    /// Waits for an unsolicited `parameterValues` in which `name` has a value `pred`
    /// accepts.
    pub fn wait_parameter(
        &mut self,
        name: &str,
        within: Duration,
        pred: impl Fn(&Value) -> bool,
    ) -> bool {
        let deadline = Instant::now() + within;
        while Instant::now() < deadline {
            if let Some(Message::Text(t)) = self.read_one() {
                let v: Value = serde_json::from_str(&t).unwrap();
                if v["op"] == "parameterValues"
                    && v["parameters"]
                        .as_array()
                        .is_some_and(|ps| ps.iter().any(|p| p["name"] == name && pred(&p["value"])))
                {
                    return true;
                }
            }
        }
        false
    }
}

impl FoxgloveClient {
    /// Reads until the server closes the connection: the code of its close frame (1005:
    /// a frame without one), or `None` when it closed without a frame (what clients
    /// report as 1006).
    pub fn wait_close(&mut self, within: Duration) -> Option<u16> {
        let end = Instant::now() + within;
        while Instant::now() < end {
            match self.ws.read() {
                Ok(Message::Close(frame)) => return Some(frame.map_or(1005, |f| f.code.into())),
                Ok(_) => {}
                Err(tungstenite::Error::Io(e))
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) => {}
                Err(_) => return None,
            }
        }
        panic!("the server did not close the connection within {within:?}");
    }

    /// Subscribes to every channel advertised so far (subscription id = channel id).
    pub fn subscribe_all(&mut self) {
        let subs: Vec<Value> = self
            .channels
            .keys()
            .map(|id| json!({"id": id, "channelId": id}))
            .collect();
        let m = json!({"op": "subscribe", "subscriptions": subs});
        self.ws
            .send(Message::Text(m.to_string().into()))
            .expect("subscribe");
    }

    /// Waits for a status message whose text contains `what`.
    pub fn wait_status_message(&mut self, what: &str, within: Duration) -> bool {
        let deadline = Instant::now() + within;
        while Instant::now() < deadline {
            if self
                .statuses
                .iter()
                .any(|s| s["message"].as_str().is_some_and(|m| m.contains(what)))
            {
                return true;
            }
            self.read_one();
        }
        false
    }
}
