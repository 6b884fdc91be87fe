//! Socket plumbing shared by discovery and the bus: socket creation and waiting.
use std::io;
use std::net::{IpAddr, Ipv4Addr, Ipv6Addr, SocketAddr, UdpSocket};
use std::os::fd::AsRawFd;
use std::time::{Duration, Instant};

use socket2::{Domain, Protocol, Socket, Type};

/// Receive buffer asked of the kernel, bytes. Large enough for a few hundred
/// milliseconds of feedback from a whole snake if the loop stalls; the kernel caps it
/// at `net.core.rmem_max` silently.
const RECV_BUFFER_BYTES: usize = 4 << 20;

/// A non-blocking UDP socket bound to `bind`, with an enlarged receive buffer and,
/// when `broadcast` is set, permission to send to broadcast addresses.
pub(super) fn open(bind: SocketAddr, broadcast: bool) -> io::Result<UdpSocket> {
    let socket = Socket::new(Domain::for_address(bind), Type::DGRAM, Some(Protocol::UDP))?;
    socket.set_nonblocking(true)?;
    // Best effort: a smaller buffer still works, it only drops sooner under a stall.
    let _ = socket.set_recv_buffer_size(RECV_BUFFER_BYTES);
    if broadcast {
        socket.set_broadcast(true)?;
    }
    socket.bind(&bind.into())?;
    Ok(socket.into())
}

/// Block until `socket` is readable or `timeout` passes (rounded up to whole ms).
/// Returns whether it became readable; an interrupted wait counts as not readable.
pub(super) fn wait_readable(socket: &UdpSocket, timeout: Duration) -> io::Result<bool> {
    let mut pfd = libc::pollfd {
        fd: socket.as_raw_fd(),
        events: libc::POLLIN,
        revents: 0,
    };
    let timeout_ms = timeout.as_nanos().div_ceil(1_000_000).min(i32::MAX as u128) as i32;
    // SAFETY: `pfd` is a valid pollfd for the duration of the call and nfds is 1.
    let r = unsafe { libc::poll(&mut pfd, 1, timeout_ms) };
    if r < 0 {
        let e = io::Error::last_os_error();
        return if e.kind() == io::ErrorKind::Interrupted {
            Ok(false)
        } else {
            Err(e)
        };
    }
    Ok(r > 0)
}

/// `timeout` from now; an absurdly long timeout means "a century", not a panic.
pub(super) fn deadline_after(timeout: Duration) -> Instant {
    let now = Instant::now();
    now.checked_add(timeout)
        .unwrap_or_else(|| now + Duration::from_secs(100 * 365 * 86_400))
}

/// Errors of `recv_from` after which draining simply continues: an ICMP error from an
/// earlier send reported on this socket, or a signal.
pub(super) fn is_transient(e: &io::Error) -> bool {
    matches!(
        e.kind(),
        io::ErrorKind::Interrupted
            | io::ErrorKind::ConnectionRefused
            | io::ErrorKind::ConnectionReset
    )
}

/// A bind address that fits `targets`: loopback when every target is on loopback,
/// otherwise the wildcard address (needed to reach broadcast targets); port 0.
pub fn default_bind(targets: &[SocketAddr]) -> SocketAddr {
    let v6 = targets.first().is_some_and(|t| t.is_ipv6());
    let all_loopback = !targets.is_empty() && targets.iter().all(|t| t.ip().is_loopback());
    let ip: IpAddr = match (v6, all_loopback) {
        (false, true) => Ipv4Addr::LOCALHOST.into(),
        (false, false) => Ipv4Addr::UNSPECIFIED.into(),
        (true, true) => Ipv6Addr::LOCALHOST.into(),
        (true, false) => Ipv6Addr::UNSPECIFIED.into(),
    };
    SocketAddr::new(ip, 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_bind_follows_targets() {
        let lo: SocketAddr = "127.0.0.1:7000".parse().unwrap();
        let bc: SocketAddr = "255.255.255.255:7000".parse().unwrap();
        assert_eq!(default_bind(&[lo]), "127.0.0.1:0".parse().unwrap());
        assert_eq!(default_bind(&[lo, bc]), "0.0.0.0:0".parse().unwrap());
        assert_eq!(
            default_bind(&["[::1]:7000".parse().unwrap()]),
            "[::1]:0".parse().unwrap()
        );
    }

    #[test]
    fn wait_readable_times_out_then_sees_data() {
        let a = open("127.0.0.1:0".parse().unwrap(), false).unwrap();
        assert!(!wait_readable(&a, Duration::from_millis(1)).unwrap());
        let b = open("127.0.0.1:0".parse().unwrap(), false).unwrap();
        b.send_to(b"x", a.local_addr().unwrap()).unwrap();
        assert!(wait_readable(&a, Duration::from_secs(2)).unwrap());
    }
}
