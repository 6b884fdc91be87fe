//! Discovery: Lookup to every target, collect the Announces, order the group head first.
use std::cmp::Ordering;
use std::io;
use std::net::{SocketAddr, UdpSocket};
use std::time::{Duration, Instant};

use super::net;
use crate::protocol::{
    Announce, DecodeError, EncodeError, Frames, Key, LookupFilter, MAX_DATAGRAM, Mac, Message,
    NO_SESSION, Name, Route, VERSION_1, encode, open,
};

/// How often the Lookup is repeated while waiting, so a lost datagram only delays.
const LOOKUP_RESEND: Duration = Duration::from_millis(100);
/// Longest wait between two looks at the stop flag: a signal during discovery ends it
/// well within 200 ms.
const STOP_POLL: Duration = Duration::from_millis(20);

/// A module that answered a lookup, and where it answered from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FoundModule {
    /// The module's endpoint (the source of its Announce).
    pub addr: SocketAddr,
    /// Which module of that endpoint it is (0 unless behind a gateway).
    pub unit: u16,
    pub announce: Announce,
}

/// Why discovery did not produce the group that was asked for.
#[derive(Debug, thiserror::Error)]
pub enum DiscoveryError {
    #[error("discovery socket: {0}")]
    Io(#[from] io::Error),
    #[error("no lookup targets given")]
    NoTargets,
    #[error("the lookup filter does not fit in one datagram: {0}")]
    FilterTooLarge(EncodeError),
    #[error("the lookup filter lists {0} twice")]
    DuplicateInFilter(String),
    #[error("no answer within {timeout:?} from: {}", .missing.join(", "))]
    Missing {
        /// The names or MACs (as `aa:bb:cc:dd:ee:ff`) that did not answer.
        missing: Vec<String>,
        timeout: Duration,
    },
    #[error("name {name} answered from several modules: {}", .macs.join(", "))]
    DuplicateName { name: String, macs: Vec<String> },
    #[error("no module answered within {0:?}")]
    NoneFound(Duration),
    #[error("expected {expected} modules, {}", answered(.found, *.timeout))]
    CountMismatch {
        expected: usize,
        /// Names of the modules that did answer.
        found: Vec<String>,
        timeout: Duration,
    },
    /// The stop flag was raised (SIGTERM, SIGINT) before the group was found.
    #[error("stopped during discovery")]
    Stopped,
    /// Only peers of the old protocol answered.
    #[error(
        "{count} datagrams of protocol v1 came from {}: those modules (or that emulator) \
         speak protocol v1, this daemon speaks v2 (docs/protocol.md)",
        .from.iter().map(ToString::to_string).collect::<Vec<_>>().join(", ")
    )]
    OldProtocol { from: Vec<SocketAddr>, count: u64 },
}

/// "none answered within …" or "N answered within …: a, b".
fn answered(found: &[String], timeout: Duration) -> String {
    if found.is_empty() {
        format!("none answered within {timeout:?}")
    } else {
        format!(
            "{} answered within {timeout:?}: {}",
            found.len(),
            found.join(", ")
        )
    }
}

/// `aa:bb:cc:dd:ee:ff`.
pub fn format_mac(mac: &Mac) -> String {
    let [a, b, c, d, e, f] = mac;
    format!("{a:02x}:{b:02x}:{c:02x}:{d:02x}:{e:02x}:{f:02x}")
}

/// Find the modules matching `filter` by sending a Lookup to every target (repeated
/// every 100 ms) and collecting Announces until `timeout`, or until the expected
/// number has answered: the length of the list for the Names / MACs filters,
/// otherwise `expected` (exact group size; `None` waits the whole timeout).
///
/// The group comes back head first: in list order for the Names / MACs filters
/// (failing with the missing entries when any did not answer), otherwise by name,
/// numbers in names compared by value (`m2` before `m10`).
/// Answers are de-duplicated by MAC. `bind` is the local address of the lookup socket
/// (see [`super::default_bind`]); the socket may send to broadcast addresses.
pub fn discover(
    targets: &[SocketAddr],
    filter: &LookupFilter,
    expected: Option<usize>,
    bind: SocketAddr,
    timeout: Duration,
) -> Result<Vec<FoundModule>, DiscoveryError> {
    let never = std::sync::atomic::AtomicBool::new(false);
    discover_until(targets, filter, expected, bind, timeout, &Key::OPEN, &never)
}

/// [`discover`] on a network keyed with `key` that gives up with
/// [`DiscoveryError::Stopped`] as soon as `stop` is set (the daemon's signal handler
/// sets it), checked at least every 20 ms.
pub fn discover_until(
    targets: &[SocketAddr],
    filter: &LookupFilter,
    expected: Option<usize>,
    bind: SocketAddr,
    timeout: Duration,
    key: &Key,
    stop: &std::sync::atomic::AtomicBool,
) -> Result<Vec<FoundModule>, DiscoveryError> {
    if targets.is_empty() {
        return Err(DiscoveryError::NoTargets);
    }
    check_filter(filter)?;
    let wanted = match filter {
        LookupFilter::Names(names) => Some(names.len()),
        LookupFilter::Macs(macs) => Some(macs.len()),
        LookupFilter::All | LookupFilter::Family(_) => expected,
    };
    let socket = net::open(bind, true)?;
    let mut tx = [0u8; MAX_DATAGRAM];
    let lookup = Message::Lookup(filter.clone());
    let route = Route {
        session: NO_SESSION,
        seq: 1,
        unit: 0,
    };
    let len = encode(route, &lookup, key, &mut tx).map_err(DiscoveryError::FilterTooLarge)?;

    let mut found: Vec<FoundModule> = Vec::new();
    let mut v1 = OldPeers::default();
    let deadline = net::deadline_after(timeout);
    let mut next_send = Instant::now();
    let mut first_round = true;
    loop {
        if stop.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(DiscoveryError::Stopped);
        }
        let now = Instant::now();
        if wanted.is_some_and(|w| found.len() >= w) || now >= deadline {
            break;
        }
        if now >= next_send {
            send_to_all(&socket, &tx[..len], targets, first_round)?;
            first_round = false;
            next_send = now + LOOKUP_RESEND;
        }
        net::wait_readable(&socket, (next_send.min(deadline) - now).min(STOP_POLL))?;
        collect(&socket, filter, key, &mut found, &mut v1)?;
    }
    match order_group(filter, expected, found, timeout) {
        Err(_) if !v1.from.is_empty() => Err(DiscoveryError::OldProtocol {
            from: v1.from,
            count: v1.count,
        }),
        r => r,
    }
}

/// Who answered in protocol v1, to say so when discovery fails.
#[derive(Default)]
struct OldPeers {
    from: Vec<SocketAddr>,
    count: u64,
}

/// Send the lookup everywhere. Failing to reach one target is not fatal (others may
/// answer); failing to reach every target on the first round is.
fn send_to_all(
    socket: &UdpSocket,
    datagram: &[u8],
    targets: &[SocketAddr],
    first_round: bool,
) -> io::Result<()> {
    let mut last_err = None;
    let mut sent = 0;
    for t in targets {
        match socket.send_to(datagram, t) {
            Ok(_) => sent += 1,
            Err(e) => last_err = Some(e),
        }
    }
    match last_err {
        Some(e) if sent == 0 && first_round => Err(e),
        _ => Ok(()),
    }
}

/// Drain the socket, keeping Announces that match the filter from MACs not yet seen.
fn collect(
    socket: &UdpSocket,
    filter: &LookupFilter,
    key: &Key,
    found: &mut Vec<FoundModule>,
    v1: &mut OldPeers,
) -> io::Result<()> {
    let mut rx = [0u8; MAX_DATAGRAM];
    loop {
        match socket.recv_from(&mut rx) {
            Ok((n, addr)) => {
                // A gateway answers for all its units in one datagram.
                for frame in Frames::new(&rx[..n]) {
                    match frame.and_then(|(h, f)| Ok((h, open(f, key)?))) {
                        Ok((h, Message::Announce(a)))
                            if matches_filter(filter, &a)
                                && !found.iter().any(|f| f.announce.mac == a.mac) =>
                        {
                            found.push(FoundModule {
                                addr,
                                unit: h.unit,
                                announce: a,
                            });
                        }
                        Err(DecodeError::WrongVersion(VERSION_1)) => {
                            v1.count += 1;
                            if !v1.from.contains(&addr) {
                                v1.from.push(addr);
                            }
                        }
                        _ => {}
                    }
                }
            }
            Err(e) if e.kind() == io::ErrorKind::WouldBlock => return Ok(()),
            Err(e) if net::is_transient(&e) => continue,
            Err(e) => return Err(e),
        }
    }
}

/// Nothing is trusted: an Announce that does not fit what was asked is ignored.
fn matches_filter(filter: &LookupFilter, a: &Announce) -> bool {
    match filter {
        LookupFilter::All => true,
        LookupFilter::Family(f) => a.family == *f,
        LookupFilter::Names(names) => names.contains(&a.name),
        LookupFilter::Macs(macs) => macs.contains(&a.mac),
    }
}

fn check_filter(filter: &LookupFilter) -> Result<(), DiscoveryError> {
    fn first_duplicate<T: PartialEq>(list: &[T]) -> Option<&T> {
        list.iter()
            .enumerate()
            .find(|(i, x)| list[..*i].contains(x))
            .map(|(_, x)| x)
    }
    let dup = match filter {
        LookupFilter::Names(names) => first_duplicate(names).map(Name::to_string),
        LookupFilter::Macs(macs) => first_duplicate(macs).map(format_mac),
        LookupFilter::All | LookupFilter::Family(_) => None,
    };
    dup.map_or(Ok(()), |d| Err(DiscoveryError::DuplicateInFilter(d)))
}

/// Order the answers head first and check that they are the group asked for.
pub(super) fn order_group(
    filter: &LookupFilter,
    expected: Option<usize>,
    mut found: Vec<FoundModule>,
    timeout: Duration,
) -> Result<Vec<FoundModule>, DiscoveryError> {
    match filter {
        LookupFilter::Names(names) => {
            let mut group = Vec::with_capacity(names.len());
            let mut missing = Vec::new();
            for name in names {
                let hits: Vec<&FoundModule> =
                    found.iter().filter(|f| f.announce.name == *name).collect();
                match hits.as_slice() {
                    [] => missing.push(name.to_string()),
                    [one] => group.push(**one),
                    many => {
                        return Err(DiscoveryError::DuplicateName {
                            name: name.to_string(),
                            macs: many.iter().map(|f| format_mac(&f.announce.mac)).collect(),
                        });
                    }
                }
            }
            if missing.is_empty() {
                Ok(group)
            } else {
                Err(DiscoveryError::Missing { missing, timeout })
            }
        }
        LookupFilter::Macs(macs) => {
            let mut group = Vec::with_capacity(macs.len());
            let mut missing = Vec::new();
            for mac in macs {
                match found.iter().find(|f| f.announce.mac == *mac) {
                    Some(f) => group.push(*f),
                    None => missing.push(format_mac(mac)),
                }
            }
            if missing.is_empty() {
                Ok(group)
            } else {
                Err(DiscoveryError::Missing { missing, timeout })
            }
        }
        LookupFilter::All | LookupFilter::Family(_) => {
            found.sort_by(|a, b| {
                natural_cmp(a.announce.name.as_str(), b.announce.name.as_str())
                    .then(a.announce.mac.cmp(&b.announce.mac))
            });
            match expected {
                None if found.is_empty() => Err(DiscoveryError::NoneFound(timeout)),
                Some(e) if e != found.len() => Err(DiscoveryError::CountMismatch {
                    expected: e,
                    found: found.iter().map(|f| f.announce.name.to_string()).collect(),
                    timeout,
                }),
                _ => Ok(found),
            }
        }
    }
}

/// Compare names with runs of digits compared by value, so `m2 < m10`; ties (such as
/// `m02` against `m2`) fall back to plain byte order.
pub(super) fn natural_cmp(a: &str, b: &str) -> Ordering {
    let (mut x, mut y) = (a.as_bytes(), b.as_bytes());
    loop {
        match (x.first(), y.first()) {
            (None, None) => return a.cmp(b),
            (None, Some(_)) => return Ordering::Less,
            (Some(_), None) => return Ordering::Greater,
            (Some(c), Some(d)) if c.is_ascii_digit() && d.is_ascii_digit() => {
                let (nx, rx) = split_digits(x);
                let (ny, ry) = split_digits(y);
                let ord = nx.len().cmp(&ny.len()).then(nx.cmp(ny));
                if ord != Ordering::Equal {
                    return ord;
                }
                (x, y) = (rx, ry);
            }
            (Some(c), Some(d)) => {
                if c != d {
                    return c.cmp(d);
                }
                (x, y) = (&x[1..], &y[1..]);
            }
        }
    }
}

/// Leading digit run without its leading zeros, and the rest.
fn split_digits(s: &[u8]) -> (&[u8], &[u8]) {
    let end = s
        .iter()
        .position(|c| !c.is_ascii_digit())
        .unwrap_or(s.len());
    let zeros = s[..end].iter().take_while(|&&c| c == b'0').count();
    (&s[zeros..end], &s[end..])
}
