//! A fake module for the bus tests: its own UDP socket and thread, speaking protocol
//! v2 through the real codec on an open network. Behaviour switches live in
//! [`FakeState`].
use std::net::{SocketAddr, UdpSocket};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::Duration;

use super::FoundModule;
use crate::protocol::{
    AcquireReply, Announce, Command, Feedback, Key, LookupFilter, MAX_DATAGRAM, Message,
    NO_SESSION, Name, Route, Settings, encode, open, peek,
};

#[derive(Debug, Default)]
pub(super) struct FakeState {
    pub owner: u32,
    pub owner_addr: Option<SocketAddr>,
    /// The owner's session key (the open key while free).
    pub key: Option<Key>,
    pub settings: Option<Settings>,
    /// Drop this many Settings before answering (a lossy link).
    pub drop_settings: u32,
    /// Acknowledge other settings than asked (a refusal).
    pub refuse_settings: bool,
    /// Answer nothing at all.
    pub silent: bool,
    /// Send one feedback per command, advancing the clock by 1 ms (emulator lockstep).
    pub lockstep: bool,
    /// Commands received from the owner: (header seq, command).
    pub commands: Vec<(u64, Command)>,
    pub wrong_session: u32,
    pub fb_seq: u64,
    pub time_us: u64,
}

pub(super) struct FakeModule {
    pub announce: Announce,
    pub addr: SocketAddr,
    socket: UdpSocket,
    state: Arc<Mutex<FakeState>>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl FakeModule {
    pub fn spawn(name: &str, family: &str, mac_last: u8) -> FakeModule {
        let socket = UdpSocket::bind("127.0.0.1:0").unwrap();
        socket
            .set_read_timeout(Some(Duration::from_millis(5)))
            .unwrap();
        let announce = Announce {
            mac: [2, 0, 0, 0, 0, mac_last],
            family: Name::new(family).unwrap(),
            name: Name::new(name).unwrap(),
            firmware: 1,
            owned: false,
        };
        let state = Arc::new(Mutex::new(FakeState::default()));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = {
            let (socket, state, stop) = (socket.try_clone().unwrap(), state.clone(), stop.clone());
            std::thread::spawn(move || serve(&socket, announce, &state, &stop))
        };
        FakeModule {
            announce,
            addr: socket.local_addr().unwrap(),
            socket,
            state,
            stop,
            thread: Some(thread),
        }
    }

    pub fn found(&self) -> FoundModule {
        FoundModule {
            addr: self.addr,
            unit: 0,
            announce: self.announce,
        }
    }

    pub fn state(&self) -> MutexGuard<'_, FakeState> {
        self.state.lock().unwrap()
    }

    /// Send raw bytes from the module's endpoint to its owner.
    pub fn send_raw(&self, bytes: &[u8]) {
        let to = self.state().owner_addr.expect("module is owned");
        self.socket.send_to(bytes, to).unwrap();
    }

    /// Send a crafted feedback to the owner, tagged under the owner's session key.
    pub fn send_feedback(&self, session: u32, seq: u64, time_us: u64) {
        let key = self.state().key.expect("module is owned");
        self.send_raw(&feedback_datagram(session, seq, time_us, &key));
    }
}

impl Drop for FakeModule {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            t.join().unwrap();
        }
    }
}

pub(super) fn feedback_datagram(session: u32, seq: u64, time_us: u64, key: &Key) -> Vec<u8> {
    let fb = Feedback {
        module_time_us: time_us,
        position_rad: 0.25,
        ..Feedback::default()
    };
    let mut buf = [0u8; MAX_DATAGRAM];
    let route = Route {
        session,
        seq,
        unit: 0,
    };
    let n = encode(route, &Message::Feedback(fb), key, &mut buf).unwrap();
    buf[..n].to_vec()
}

fn serve(socket: &UdpSocket, announce: Announce, state: &Mutex<FakeState>, stop: &AtomicBool) {
    let mut buf = [0u8; MAX_DATAGRAM];
    while !stop.load(Ordering::Relaxed) {
        let Ok((n, src)) = socket.recv_from(&mut buf) else {
            continue;
        };
        let Ok((h, _)) = peek(&buf[..n]) else {
            continue;
        };
        let mut st = state.lock().unwrap();
        if st.silent {
            continue;
        }
        let owned_by_sender = h.session != NO_SESSION && h.session == st.owner;
        let key = match (h.msg_type.uses_network_key(), st.key) {
            (false, Some(k)) if owned_by_sender => k,
            _ => Key::OPEN,
        };
        let Ok(msg) = open(&buf[..n], &key) else {
            if !h.msg_type.uses_network_key() {
                st.wrong_session += 1;
            }
            continue;
        };
        let mut out: Vec<(u32, u64, Message)> = Vec::new();
        match msg {
            Message::Lookup(filter) => {
                let hit = match &filter {
                    LookupFilter::All => true,
                    LookupFilter::Family(f) => *f == announce.family,
                    LookupFilter::Names(n) => n.contains(&announce.name),
                    LookupFilter::Macs(m) => m.contains(&announce.mac),
                };
                if hit {
                    let a = Announce {
                        owned: st.owner != NO_SESSION,
                        ..announce
                    };
                    out.push((NO_SESSION, h.seq, Message::Announce(a)));
                }
            }
            Message::Acquire(host_nonce) => {
                let granted =
                    h.session != NO_SESSION && (st.owner == NO_SESSION || owned_by_sender);
                let module_nonce = [h.session as u8; 16];
                if granted {
                    st.owner = h.session;
                    st.owner_addr = Some(src);
                    st.key = Some(Key::OPEN.session_key(
                        h.session,
                        &announce.mac,
                        &host_nonce,
                        &module_nonce,
                    ));
                }
                let reply = AcquireReply {
                    granted,
                    module_nonce: if granted { module_nonce } else { [0; 16] },
                };
                out.push((h.session, h.seq, Message::AcquireReply(reply)));
            }
            _ if !owned_by_sender => st.wrong_session += 1,
            Message::Release => {
                st.owner = NO_SESSION;
                st.owner_addr = None;
                st.key = None;
            }
            Message::Settings(_) if st.drop_settings > 0 => st.drop_settings -= 1,
            Message::Settings(s) => {
                let ack = if st.refuse_settings {
                    Settings {
                        feedback_rate_hz: 1.0,
                        ..s
                    }
                } else {
                    st.settings = Some(s);
                    s
                };
                out.push((st.owner, h.seq, Message::SettingsAck(ack)));
                out.push(next_feedback(&mut st));
            }
            Message::Command(c) => {
                st.commands.push((h.seq, c));
                if st.lockstep {
                    st.time_us += 1000;
                    out.push(next_feedback(&mut st));
                }
            }
            _ => {}
        }
        // Feedback goes to the owner, replies to the sender.
        let fb_to = st.owner_addr;
        let session_key = st.key.unwrap_or(Key::OPEN);
        drop(st);
        for (session, seq, m) in out {
            let to = match &m {
                Message::Feedback(_) => fb_to.unwrap_or(src),
                _ => src,
            };
            let key = if m.msg_type().uses_network_key() {
                Key::OPEN
            } else {
                session_key
            };
            let mut tx = [0u8; MAX_DATAGRAM];
            let route = Route {
                session,
                seq,
                unit: 0,
            };
            let len = encode(route, &m, &key, &mut tx).unwrap();
            let _ = socket.send_to(&tx[..len], to);
        }
    }
}

/// The next streamed feedback (session, seq, message): bumps the feedback seq.
fn next_feedback(st: &mut FakeState) -> (u32, u64, Message) {
    st.fb_seq += 1;
    let fb = Feedback {
        module_time_us: st.time_us,
        last_command_seq: st.commands.last().map_or(0, |c| c.0),
        ..Feedback::default()
    };
    (st.owner, st.fb_seq, Message::Feedback(fb))
}
