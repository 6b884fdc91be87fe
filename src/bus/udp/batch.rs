//! Receiving many datagrams in one system call (`recvmmsg(2)`), each with the kernel's
//! receive timestamp (`SO_TIMESTAMPNS`): the loop drains a whole group's feedback in
//! one call, and a datagram's age counts from when it reached the machine, not from
//! when the loop got round to it. Buffers are allocated once.
use std::io;
use std::mem::{size_of, zeroed};
use std::net::{Ipv4Addr, Ipv6Addr, SocketAddr, SocketAddrV4, SocketAddrV6, UdpSocket};
use std::os::fd::AsRawFd;

use crate::protocol::MAX_DATAGRAM;

/// Datagrams per call: more than an 18-module group sends per cycle.
pub(super) const BATCH: usize = 32;
/// One byte more than the largest datagram, to see oversized ones.
pub(super) const SLOT: usize = MAX_DATAGRAM + 1;
/// Room for one `SCM_TIMESTAMPNS` control message (a timespec), aligned.
const CONTROL: usize = 64;

/// One received datagram.
pub(super) struct Datagram<'a> {
    pub bytes: &'a [u8],
    /// Longer than a slot: cut by the kernel, to be counted as too long.
    pub oversized: bool,
    pub from: Option<SocketAddr>,
    /// Kernel receive time, ns on `CLOCK_REALTIME` (0 when the kernel gave none).
    pub rx_realtime_ns: u64,
}

pub(super) struct RecvBatch {
    bufs: Box<[[u8; SLOT]]>,
    addrs: Box<[libc::sockaddr_storage]>,
    controls: Box<[[u64; CONTROL / 8]]>,
    iov: Box<[libc::iovec]>,
    msgs: Box<[libc::mmsghdr]>,
}

// SAFETY: the raw pointers in `iov` and `msgs` point into the boxes this struct owns
// and are rewritten before every use; nothing is shared between threads.
unsafe impl Send for RecvBatch {}

impl RecvBatch {
    pub fn new() -> Self {
        // SAFETY: all-zero is a valid value of these plain C structs.
        let zero_msg = || unsafe { zeroed::<libc::mmsghdr>() };
        let zero_addr = || unsafe { zeroed::<libc::sockaddr_storage>() };
        Self {
            bufs: vec![[0; SLOT]; BATCH].into_boxed_slice(),
            addrs: (0..BATCH).map(|_| zero_addr()).collect(),
            controls: vec![[0; CONTROL / 8]; BATCH].into_boxed_slice(),
            iov: (0..BATCH)
                .map(|_| libc::iovec {
                    iov_base: std::ptr::null_mut(),
                    iov_len: 0,
                })
                .collect(),
            msgs: (0..BATCH).map(|_| zero_msg()).collect(),
        }
    }

    /// Ask the kernel to stamp every datagram `socket` receives.
    pub fn enable_timestamps(socket: &UdpSocket) -> io::Result<()> {
        let on: libc::c_int = 1;
        // SAFETY: a valid fd, option and pointer to an int of the size given.
        let r = unsafe {
            libc::setsockopt(
                socket.as_raw_fd(),
                libc::SOL_SOCKET,
                libc::SO_TIMESTAMPNS,
                (&on as *const libc::c_int).cast(),
                size_of::<libc::c_int>() as libc::socklen_t,
            )
        };
        if r < 0 {
            return Err(io::Error::last_os_error());
        }
        Ok(())
    }

    /// Receive what is waiting, up to [`BATCH`] datagrams, without blocking; returns
    /// how many (0: nothing waiting). Fewer than `BATCH` means the socket is empty.
    pub fn recv(&mut self, socket: &UdpSocket) -> io::Result<usize> {
        for i in 0..BATCH {
            self.iov[i] = libc::iovec {
                iov_base: self.bufs[i].as_mut_ptr().cast(),
                iov_len: SLOT,
            };
            let h = &mut self.msgs[i].msg_hdr;
            h.msg_name = (&mut self.addrs[i] as *mut libc::sockaddr_storage).cast();
            h.msg_namelen = size_of::<libc::sockaddr_storage>() as libc::socklen_t;
            h.msg_iov = &mut self.iov[i];
            h.msg_iovlen = 1;
            h.msg_control = self.controls[i].as_mut_ptr().cast();
            h.msg_controllen = CONTROL as _;
            h.msg_flags = 0;
            self.msgs[i].msg_len = 0;
        }
        // SAFETY: `msgs` holds BATCH initialised headers whose pointers all point into
        // buffers owned by `self` of the sizes given; the fd is valid.
        let r = unsafe {
            libc::recvmmsg(
                socket.as_raw_fd(),
                self.msgs.as_mut_ptr(),
                BATCH as libc::c_uint,
                libc::MSG_DONTWAIT,
                std::ptr::null_mut(),
            )
        };
        if r < 0 {
            let e = io::Error::last_os_error();
            return if e.kind() == io::ErrorKind::WouldBlock {
                Ok(0)
            } else {
                Err(e)
            };
        }
        Ok(r as usize)
    }

    /// Datagram `i` of the last [`RecvBatch::recv`].
    pub fn get(&self, i: usize) -> Datagram<'_> {
        let m = &self.msgs[i];
        let len = (m.msg_len as usize).min(SLOT);
        Datagram {
            bytes: &self.bufs[i][..len],
            oversized: m.msg_hdr.msg_flags & libc::MSG_TRUNC != 0 || len > MAX_DATAGRAM,
            from: to_socket_addr(&self.addrs[i]),
            rx_realtime_ns: timestamp_ns(&m.msg_hdr),
        }
    }
}

fn to_socket_addr(s: &libc::sockaddr_storage) -> Option<SocketAddr> {
    match i32::from(s.ss_family) {
        libc::AF_INET => {
            // SAFETY: the family says the storage holds a sockaddr_in.
            let a = unsafe { &*(s as *const libc::sockaddr_storage).cast::<libc::sockaddr_in>() };
            let ip = Ipv4Addr::from(u32::from_be(a.sin_addr.s_addr));
            Some(SocketAddrV4::new(ip, u16::from_be(a.sin_port)).into())
        }
        libc::AF_INET6 => {
            // SAFETY: the family says the storage holds a sockaddr_in6.
            let a = unsafe { &*(s as *const libc::sockaddr_storage).cast::<libc::sockaddr_in6>() };
            let ip = Ipv6Addr::from(a.sin6_addr.s6_addr);
            let port = u16::from_be(a.sin6_port);
            Some(SocketAddrV6::new(ip, port, a.sin6_flowinfo, a.sin6_scope_id).into())
        }
        _ => None,
    }
}

/// The `SCM_TIMESTAMPNS` of a received message, ns on `CLOCK_REALTIME`; 0 if none.
fn timestamp_ns(h: &libc::msghdr) -> u64 {
    // SAFETY: `h` is a header the kernel just filled; the CMSG macros walk its control
    // buffer within `msg_controllen`.
    unsafe {
        let mut c = libc::CMSG_FIRSTHDR(h);
        while !c.is_null() {
            if (*c).cmsg_level == libc::SOL_SOCKET && (*c).cmsg_type == libc::SCM_TIMESTAMPNS {
                let ts = std::ptr::read_unaligned(libc::CMSG_DATA(c).cast::<libc::timespec>());
                return ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64;
            }
            c = libc::CMSG_NXTHDR(h, c);
        }
    }
    0
}

/// `CLOCK_REALTIME` now, ns.
pub(super) fn realtime_ns() -> u64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: valid pointer to a timespec; CLOCK_REALTIME always exists on Linux.
    unsafe { libc::clock_gettime(libc::CLOCK_REALTIME, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_call_takes_several_datagrams_with_their_senders_and_times() {
        let rx = UdpSocket::bind("127.0.0.1:0").unwrap();
        RecvBatch::enable_timestamps(&rx).unwrap();
        let tx = UdpSocket::bind("127.0.0.1:0").unwrap();
        let mut b = RecvBatch::new();
        assert_eq!(b.recv(&rx).unwrap(), 0);
        let before = realtime_ns();
        for k in 0..3u8 {
            tx.send_to(&[k; 10], rx.local_addr().unwrap()).unwrap();
        }
        tx.send_to(&vec![7; SLOT + 5], rx.local_addr().unwrap())
            .unwrap();
        let mut got = 0;
        while got < 4 {
            let n = b.recv(&rx).unwrap();
            for i in 0..n {
                let d = b.get(i);
                assert_eq!(d.from, Some(tx.local_addr().unwrap()));
                assert!(d.rx_realtime_ns >= before, "stamped on arrival");
                assert!(d.rx_realtime_ns <= realtime_ns());
                if got + i < 3 {
                    assert_eq!(d.bytes, &[(got + i) as u8; 10]);
                    assert!(!d.oversized);
                } else {
                    assert!(d.oversized);
                }
            }
            got += n;
        }
    }
}
