//! The one error of every operator path (the control socket, the Foxglove station, the
//! navigator, a ROS 2 node) and the one table of its codes (JSON-RPC 2.0 style; see
//! `docs/control-socket.md`, "Errors").

use serde::Serialize;

/// Error codes. Every edge answers with these (the socket in its error objects, the
/// station in its service errors).
pub mod code {
    /// The line is not valid JSON.
    pub const PARSE_ERROR: i64 = -32700;
    /// Not an object, or `id` / `method` missing or of the wrong type.
    pub const INVALID_REQUEST: i64 = -32600;
    /// No such method.
    pub const METHOD_NOT_FOUND: i64 = -32601;
    /// A param has the wrong type, is unknown, out of range or not finite.
    pub const INVALID_PARAMS: i64 = -32602;
    /// The loop's request channel is full; try again.
    pub const BUSY: i64 = -32000;
    /// The loop did not answer within the server's ack timeout.
    pub const LOOP_TIMEOUT: i64 = -32001;
    /// The loop refused the request (or is not running).
    pub const REFUSED: i64 = -32002;
    /// The line exceeded `max_line_bytes`; it was discarded up to its newline.
    pub const LINE_TOO_LONG: i64 = -32003;
    /// The server already serves `max_clients` connections; it closes this one.
    pub const TOO_MANY_CLIENTS: i64 = -32004;
    /// A client called a method before authenticating (`auth`), or with a wrong token.
    pub const UNAUTHORIZED: i64 = -32005;
    /// Another client drives (`operator::driver`): a driving request is refused until
    /// it stops, leaves or lapses, or this client calls `take_over`.
    pub const DRIVEN_BY_OTHER: i64 = -32006;
    /// The operator API is not running yet (a station client early at start-up).
    pub const NOT_READY: i64 = -32007;
}

/// An error answer: `{"code": .., "message": ".."}`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, thiserror::Error)]
#[error("error {code}: {message}")]
pub struct OperatorError {
    pub code: i64,
    pub message: String,
}

impl OperatorError {
    pub fn new(code: i64, message: impl Into<String>) -> Self {
        Self {
            code,
            message: message.into(),
        }
    }

    pub fn invalid_params(message: impl Into<String>) -> Self {
        Self::new(code::INVALID_PARAMS, message)
    }
}

#[cfg(test)]
mod tests {
    use super::code::*;

    /// One table: no two meanings share a code.
    #[test]
    fn every_code_is_distinct() {
        let mut all = [
            PARSE_ERROR,
            INVALID_REQUEST,
            METHOD_NOT_FOUND,
            INVALID_PARAMS,
            BUSY,
            LOOP_TIMEOUT,
            REFUSED,
            LINE_TOO_LONG,
            TOO_MANY_CLIENTS,
            UNAUTHORIZED,
            DRIVEN_BY_OTHER,
            NOT_READY,
        ];
        all.sort_unstable();
        assert!(all.windows(2).all(|w| w[0] != w[1]), "{all:?}");
    }
}
