//! A v2 host spoken by hand against the UDP emulator (`Running`, `Client`), shared by
//! the emulator's end-to-end tests.

use std::collections::{HashMap, VecDeque};
use std::net::{SocketAddr, UdpSocket};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use snaked::emu::plant::{JointSpacePlant, PlantConfig};
use snaked::emu::server::{Server, ServerConfig, ServerCounters};
use snaked::protocol::{
    AcquireReply, Feedback, Frames, Header, Key, LookupFilter, MAX_DATAGRAM, Message, Route,
    Settings, encode, open,
};

pub const S: u32 = 0x5EED;

pub struct Running {
    pub addrs: Vec<SocketAddr>,
    stop: Arc<AtomicBool>,
    handle: JoinHandle<ServerCounters>,
}

impl Running {
    pub fn start(config: ServerConfig, plant: PlantConfig) -> Self {
        let plant = JointSpacePlant::new(plant).unwrap();
        let mut server = Server::new(config, Box::new(plant)).unwrap();
        let addrs = server.local_addrs().unwrap();
        let stop = Arc::new(AtomicBool::new(false));
        let flag = stop.clone();
        let handle = std::thread::spawn(move || server.run(&flag).unwrap());
        Self {
            addrs,
            stop,
            handle,
        }
    }

    pub fn stop(self) -> ServerCounters {
        self.stop.store(true, Ordering::Relaxed);
        self.handle.join().unwrap()
    }
}

/// A host speaking v2 by hand: one session, a session key per module it acquired
/// (by address and unit), frames of bundled datagrams queued one by one.
pub struct Client {
    pub sock: UdpSocket,
    seq: u64,
    network_key: Key,
    host_nonce: [u8; 16],
    /// (address, unit) → session key.
    keys: HashMap<(SocketAddr, u16), Key>,
    /// (address, unit) → MAC, learned from announces.
    macs: HashMap<(SocketAddr, u16), [u8; 6]>,
    queue: VecDeque<(SocketAddr, Header, Message)>,
    /// Datagrams and frames received so far.
    pub datagrams: usize,
    pub frames: usize,
}

impl Client {
    pub fn new() -> Self {
        Self::keyed(Key::OPEN)
    }

    pub fn keyed(network_key: Key) -> Self {
        let sock = UdpSocket::bind("127.0.0.1:0").unwrap();
        sock.set_read_timeout(Some(Duration::from_millis(20)))
            .unwrap();
        Self {
            sock,
            seq: 0,
            network_key,
            host_nonce: [0x11; 16],
            keys: HashMap::new(),
            macs: HashMap::new(),
            queue: VecDeque::new(),
            datagrams: 0,
            frames: 0,
        }
    }

    pub fn key(&self, msg: &Message, to: SocketAddr, unit: u16) -> Key {
        if msg.msg_type().uses_network_key() {
            self.network_key
        } else {
            self.keys.get(&(to, unit)).copied().unwrap_or(Key::OPEN)
        }
    }

    /// Encode one frame (not sent).
    pub fn frame(&mut self, to: SocketAddr, unit: u16, session: u32, msg: &Message) -> Vec<u8> {
        self.seq += 1;
        let mut buf = [0u8; MAX_DATAGRAM];
        let key = self.key(msg, to, unit);
        let r = Route {
            session,
            seq: self.seq,
            unit,
        };
        let n = encode(r, msg, &key, &mut buf).unwrap();
        buf[..n].to_vec()
    }

    pub fn send(&mut self, to: SocketAddr, session: u32, msg: &Message) -> u64 {
        self.send_unit(to, 0, session, msg)
    }

    pub fn send_unit(&mut self, to: SocketAddr, unit: u16, session: u32, msg: &Message) -> u64 {
        let d = self.frame(to, unit, session, msg);
        self.sock.send_to(&d, to).unwrap();
        self.seq
    }

    /// Next frame within `within`, checked and decoded.
    pub fn recv(&mut self, within: Duration) -> Option<(SocketAddr, Header, Message)> {
        let end = Instant::now() + within;
        let mut buf = [0u8; 2048];
        while self.queue.is_empty() && Instant::now() < end {
            if let Ok((n, from)) = self.sock.recv_from(&mut buf) {
                self.datagrams += 1;
                for f in Frames::new(&buf[..n]) {
                    self.frames += 1;
                    let (h, frame) = f.expect("emulator sent a valid frame");
                    let key = if h.msg_type.uses_network_key() {
                        self.network_key
                    } else {
                        self.keys[&(from, h.unit)]
                    };
                    let m = open(frame, &key).expect("emulator tagged it right");
                    if let Message::Announce(a) = &m {
                        self.macs.insert((from, h.unit), a.mac);
                    }
                    self.queue.push_back((from, h, m));
                }
            }
        }
        self.queue.pop_front()
    }

    /// Next message that is not feedback (replies), skipping streamed feedback.
    pub fn reply(&mut self) -> Option<(SocketAddr, Header, Message)> {
        let end = Instant::now() + Duration::from_secs(2);
        while Instant::now() < end {
            match self.recv(Duration::from_millis(100)) {
                Some((_, _, Message::Feedback(_))) => continue,
                other @ Some(_) => return other,
                None => {}
            }
        }
        None
    }

    /// Every feedback from the module at `from` received during `within`.
    pub fn feedback_from(&mut self, from: SocketAddr, within: Duration) -> Vec<(Header, Feedback)> {
        let end = Instant::now() + within;
        let mut out = Vec::new();
        while Instant::now() < end {
            if let Some((a, h, Message::Feedback(f))) = self.recv(Duration::from_millis(10))
                && a == from
            {
                out.push((h, f));
            }
        }
        out
    }

    /// Look the unit up (for its MAC), acquire it, derive its session key.
    pub fn acquire_unit(&mut self, to: SocketAddr, unit: u16) {
        if !self.macs.contains_key(&(to, unit)) {
            self.send(to, 0, &Message::Lookup(LookupFilter::All));
            while !self.macs.contains_key(&(to, unit)) {
                self.reply().expect("announce");
            }
        }
        self.send_unit(to, unit, S, &Message::Acquire(self.host_nonce));
        // Announces of the other units of a gateway may still be queued.
        let (from, h, msg) = loop {
            let r = self.reply().expect("acquire reply");
            if !matches!(r.2, Message::Announce(_)) {
                break r;
            }
        };
        assert_eq!((from, h.unit), (to, unit));
        assert_eq!(h.session, S);
        let Message::AcquireReply(AcquireReply {
            granted: true,
            module_nonce,
        }) = msg
        else {
            panic!("not granted: {msg:?}")
        };
        let mac = self.macs[&(to, unit)];
        let key = self
            .network_key
            .session_key(S, &mac, &self.host_nonce, &module_nonce);
        self.keys.insert((to, unit), key);
    }

    pub fn acquire(&mut self, to: SocketAddr) {
        self.acquire_unit(to, 0);
    }

    pub fn settings(&mut self, to: SocketAddr, s: Settings) {
        self.send(to, S, &Message::Settings(s));
        let (_, _, msg) = self.reply().expect("settings ack");
        assert_eq!(msg, Message::SettingsAck(s));
    }
}
