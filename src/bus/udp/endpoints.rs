//! Where the group's modules live on the network: each module is an address plus its
//! unit there (unit 0 for a module that is its own endpoint, 0..n behind a gateway).
//! Frames to the modules behind one address are bundled into as few datagrams as fit.
use std::collections::HashMap;
use std::net::{SocketAddr, UdpSocket};

use super::FoundModule;
use crate::protocol::{EncodeError, MAX_DATAGRAM};

/// The group's endpoints, built once at connect.
#[derive(Debug)]
pub(super) struct Endpoints {
    /// Distinct addresses, in the order of their first module.
    addrs: Vec<SocketAddr>,
    /// Per endpoint: the modules behind it, head first.
    members: Vec<Vec<usize>>,
    /// (address, unit) → module index. Only these may speak for a module.
    index: HashMap<(SocketAddr, u16), usize>,
}

/// Frames handed to the kernel, and frames that could not be (encoding refused, or
/// the send failed).
#[derive(Debug, Default, Clone, Copy, PartialEq, Eq)]
pub(super) struct SendTally {
    pub sent_frames: u64,
    pub failed_frames: u64,
}

impl Endpoints {
    /// Fails with the first (address, unit) two modules share.
    pub fn new(modules: &[FoundModule]) -> Result<Self, (SocketAddr, u16)> {
        let mut e = Endpoints {
            addrs: Vec::new(),
            members: Vec::new(),
            index: HashMap::with_capacity(modules.len()),
        };
        for (i, m) in modules.iter().enumerate() {
            if e.index.insert((m.addr, m.unit), i).is_some() {
                return Err((m.addr, m.unit));
            }
            match e.addrs.iter().position(|a| *a == m.addr) {
                Some(k) => e.members[k].push(i),
                None => {
                    e.addrs.push(m.addr);
                    e.members.push(vec![i]);
                }
            }
        }
        Ok(e)
    }

    /// The module that `addr` speaks for as `unit`.
    pub fn module_at(&self, addr: SocketAddr, unit: u16) -> Option<usize> {
        self.index.get(&(addr, unit)).copied()
    }

    /// Send one frame to every module `select` picks, bundled per endpoint: `encode`
    /// writes module `i`'s frame at the start of the slice it gets and returns its
    /// length. Never allocates.
    pub fn send_bundled<T>(
        &self,
        socket: &UdpSocket,
        buf: &mut [u8; MAX_DATAGRAM],
        select: impl Fn(usize) -> Option<T>,
        mut encode: impl FnMut(usize, T, &mut [u8]) -> Result<usize, EncodeError>,
    ) -> SendTally
    where
        T: Copy,
    {
        let mut tally = SendTally::default();
        for (addr, members) in self.addrs.iter().zip(&self.members) {
            let (mut len, mut frames) = (0, 0);
            for &i in members {
                let Some(v) = select(i) else { continue };
                let mut r = encode(i, v, &mut buf[len..]);
                if r == Err(EncodeError::BufferTooSmall) && frames > 0 {
                    flush(socket, &buf[..len], *addr, frames, &mut tally);
                    (len, frames) = (0, 0);
                    r = encode(i, v, &mut buf[..]);
                }
                match r {
                    Ok(n) => {
                        len += n;
                        frames += 1;
                    }
                    Err(_) => tally.failed_frames += 1,
                }
            }
            flush(socket, &buf[..len], *addr, frames, &mut tally);
        }
        tally
    }
}

fn flush(socket: &UdpSocket, datagram: &[u8], to: SocketAddr, frames: u64, t: &mut SendTally) {
    if frames == 0 {
        return;
    }
    match socket.send_to(datagram, to) {
        Ok(_) => t.sent_frames += frames,
        // Would block, unreachable: the frames are lost like a lost datagram.
        Err(_) => t.failed_frames += frames,
    }
}
