//! What every connection shares: the operator API and the socket's own settings.
use crate::operator::Operator;

pub(crate) struct Shared {
    /// Everything a request does goes through it.
    pub(crate) op: Operator,
    pub(crate) max_line_bytes: usize,
    /// Close a connection idle this long (no request, no stream).
    pub(crate) idle_timeout: Option<std::time::Duration>,
    /// The token TCP clients must send (`auth`) before anything else.
    pub(crate) tcp_token: Option<String>,
}
