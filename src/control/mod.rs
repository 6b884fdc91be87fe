//! The control socket: newline-delimited JSON over a Unix socket (and optionally
//! TCP on 127.0.0.1), served by tokio, feeding the loop through a bounded channel.
