//! The emulator's datagrams: receiving (every frame of a datagram to the module its
//! endpoint and unit name, tag checked under the key the module names) and sending
//! (frames to one destination bundled per endpoint, flushed once per tick).
use std::net::SocketAddr;

use super::{Server, VERSION_1};
use crate::emu::module::{ModuleTime, Outgoing};
use crate::protocol::{self, DecodeError, Header, MAX_DATAGRAM, Message, MsgType, Route};

impl Server {
    /// Read every socket until it would block, handling each datagram; replies go
    /// out at once.
    pub(super) fn drain_all(&mut self) {
        for e in 0..self.sockets.len() {
            loop {
                match self.sockets[e].recv_from(&mut self.recv_buf) {
                    Ok((len, from)) => self.on_datagram(e, len, from),
                    Err(err) if err.kind() == std::io::ErrorKind::WouldBlock => break,
                    Err(_) => {
                        // E.g. an ICMP error queued on the socket: count, move on.
                        self.counters.recv_errors += 1;
                        break;
                    }
                }
            }
        }
        self.flush_all();
    }

    /// The module that endpoint `e` serves as `unit`.
    fn module_at(&self, e: usize, unit: u16) -> Option<usize> {
        let i = if self.config.gateway {
            usize::from(unit)
        } else if unit == 0 {
            e
        } else {
            return None;
        };
        (i < self.modules.len()).then_some(i)
    }

    /// The endpoint and unit of module `i`.
    fn endpoint_of(&self, i: usize) -> (usize, u16) {
        if self.config.gateway {
            (0, i as u16) // `new` checked that every module has a unit
        } else {
            (i, 0)
        }
    }

    fn on_datagram(&mut self, e: usize, len: usize, from: SocketAddr) {
        self.counters.received += 1;
        if len > MAX_DATAGRAM {
            self.counters.bad_length += 1;
            return;
        }
        let now = self.now();
        let mut at = 0;
        while at < len {
            // A bad header ends the datagram: nothing after it can be framed.
            let (header, frame_len) = match protocol::peek(&self.recv_buf[at..len]) {
                Ok(h) => h,
                Err(err) => return self.count_decode_error(err, from),
            };
            let frame = at..at + frame_len;
            at += frame_len;
            if header.msg_type == MsgType::Lookup && self.config.gateway {
                // A lookup asks the endpoint: every unit behind the gateway answers.
                for i in 0..self.modules.len() {
                    self.on_frame(i, &header, frame.clone(), now, from);
                }
                continue;
            }
            let Some(i) = self.module_at(e, header.unit) else {
                self.counters.bad_unit += 1;
                continue;
            };
            self.on_frame(i, &header, frame, now, from);
        }
    }

    /// One frame (bytes `frame` of the receive buffer) for module `i`.
    fn on_frame(
        &mut self,
        i: usize,
        header: &Header,
        frame: std::ops::Range<usize>,
        now: ModuleTime,
        from: SocketAddr,
    ) {
        if self.faults.is_silent(i, now.sim_s) {
            self.counters.dropped_silent += 1;
            return;
        }
        let Some(key) = self.modules[i].key_for(header) else {
            // Not the owner's session: nothing to check its tag with.
            self.modules[i].count_wrong_session();
            return;
        };
        let msg = match protocol::open(&self.recv_buf[frame], &key) {
            Ok(m) => m,
            Err(err) => return self.count_decode_error(err, from),
        };
        if matches!(msg, Message::Command(_)) && self.faults.lose() {
            self.counters.dropped_command_loss += 1;
            return;
        }
        if let Some(reply) = self.modules[i].handle(now, from, header, &msg) {
            self.send(i, &reply);
        }
    }

    fn count_decode_error(&mut self, e: DecodeError, from: SocketAddr) {
        if e == DecodeError::WrongVersion(VERSION_1) && self.counters.v1_refused == 0 {
            tracing::warn!(
                "refusing protocol v1 datagrams from {from}: this emulator speaks v2 \
                 (docs/protocol.md); counted as v1_refused"
            );
        }
        self.counters.count_decode_error(e);
    }

    /// Queue `out` from module `i` in its endpoint's outbox: frames to the same
    /// destination share a datagram while they fit.
    pub(super) fn send(&mut self, i: usize, out: &Outgoing) {
        let (e, unit) = self.endpoint_of(i);
        if self.outboxes[e].dest != Some(out.dest) {
            self.flush(e);
        }
        let route = Route {
            session: out.session,
            seq: out.seq,
            unit,
        };
        for attempt in 0..2 {
            let ob = &mut self.outboxes[e];
            match protocol::encode(route, &out.message, &out.key, &mut ob.buf[ob.len..]) {
                Ok(n) => {
                    ob.len += n;
                    ob.dest = Some(out.dest);
                    if !self.config.gateway {
                        self.flush(e);
                    }
                    return;
                }
                Err(protocol::EncodeError::BufferTooSmall) if attempt == 0 => self.flush(e),
                Err(_) => break,
            }
        }
        self.counters.send_errors += 1;
    }

    fn flush(&mut self, e: usize) {
        let ob = &mut self.outboxes[e];
        if let Some(dest) = ob.dest.take()
            && ob.len > 0
        {
            match self.sockets[e].send_to(&ob.buf[..ob.len], dest) {
                Ok(_) => self.counters.sent += 1,
                Err(_) => self.counters.send_errors += 1,
            }
        }
        ob.len = 0;
    }

    pub(super) fn flush_all(&mut self) {
        for e in 0..self.outboxes.len() {
            self.flush(e);
        }
    }
}
