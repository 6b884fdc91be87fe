//! Waiting for datagrams on many sockets without spinning: `poll(2)`.

use std::net::UdpSocket;
use std::os::fd::AsRawFd;

/// The sockets' poll set, built once.
pub struct PollSet {
    fds: Vec<libc::pollfd>,
}

impl PollSet {
    pub fn new(sockets: &[UdpSocket]) -> Self {
        let fds = sockets
            .iter()
            .map(|s| libc::pollfd {
                fd: s.as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            })
            .collect();
        Self { fds }
    }

    /// Wait up to `timeout_ms` until at least one socket is readable. Returns how many
    /// are (0 on timeout or when a signal interrupted the wait).
    pub fn wait(&mut self, timeout_ms: i32) -> std::io::Result<usize> {
        for fd in &mut self.fds {
            fd.revents = 0;
        }
        // SAFETY: `fds` is a live, initialised slice of pollfds of the given length,
        // and the sockets they name outlive this set (both are owned by the server).
        let rc = unsafe {
            libc::poll(
                self.fds.as_mut_ptr(),
                self.fds.len() as libc::nfds_t,
                timeout_ms,
            )
        };
        if rc < 0 {
            let e = std::io::Error::last_os_error();
            return if e.kind() == std::io::ErrorKind::Interrupted {
                Ok(0)
            } else {
                Err(e)
            };
        }
        Ok(rc as usize)
    }
}
