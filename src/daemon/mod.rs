//! Wiring of the daemon: configuration, discovery, the loop thread, the socket
//! server and the service manager.
