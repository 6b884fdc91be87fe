//! Parsing of lookup targets: where discovery sends its Lookup.
use std::net::{IpAddr, SocketAddr};

/// Most ports one range may name (a typo like `7000-70000` should not send 63 000
/// lookups).
pub const MAX_RANGE_PORTS: usize = 1024;

/// Why a target list was rejected. Each variant names the offending item.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TargetError {
    #[error("no lookup targets given")]
    Empty,
    #[error(
        "target {0:?}: expected IP:PORT or IP:FIRST-LAST \
         (e.g. 127.0.0.1:7000, 127.0.0.1:7000-7017, [::1]:7000, 255.255.255.255:7000)"
    )]
    Syntax(String),
    #[error("target {item:?}: {ip:?} is not an IP address (host names are not resolved)")]
    BadIp { item: String, ip: String },
    #[error("target {item:?}: {port:?} is not a port number 1-65535")]
    BadPort { item: String, port: String },
    #[error("target {item:?}: port range {first}-{last} runs backwards")]
    ReversedRange { item: String, first: u16, last: u16 },
    #[error("target {item:?}: range of {count} ports, more than {MAX_RANGE_PORTS}")]
    RangeTooLong { item: String, count: usize },
}

/// Parse a list of lookup targets separated by commas or white space. Each item is
/// `IP:PORT` or `IP:FIRST-LAST` (every port of the inclusive range); IPv6 addresses go
/// in brackets. Broadcast addresses are ordinary targets. Duplicates are dropped,
/// order is kept.
pub fn parse_targets(s: &str) -> Result<Vec<SocketAddr>, TargetError> {
    let mut out: Vec<SocketAddr> = Vec::new();
    for item in s
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|i| !i.is_empty())
    {
        for addr in parse_item(item)? {
            if !out.contains(&addr) {
                out.push(addr);
            }
        }
    }
    if out.is_empty() {
        return Err(TargetError::Empty);
    }
    Ok(out)
}

fn parse_item(item: &str) -> Result<Vec<SocketAddr>, TargetError> {
    let syntax = || TargetError::Syntax(item.to_string());
    let (host, ports) = item.rsplit_once(':').ok_or_else(syntax)?;
    let host = match host.strip_prefix('[') {
        Some(h) => h.strip_suffix(']').ok_or_else(syntax)?,
        // An unbracketed IPv6 address would be ambiguous with the port.
        None if host.contains(':') => return Err(syntax()),
        None => host,
    };
    if host.is_empty() || ports.is_empty() {
        return Err(syntax());
    }
    let ip: IpAddr = host.parse().map_err(|_| TargetError::BadIp {
        item: item.to_string(),
        ip: host.to_string(),
    })?;
    let port = |p: &str| match p.trim().parse::<u16>() {
        Ok(n) if n != 0 => Ok(n),
        _ => Err(TargetError::BadPort {
            item: item.to_string(),
            port: p.to_string(),
        }),
    };
    let (first, last) = match ports.split_once('-') {
        Some((a, b)) => (port(a)?, port(b)?),
        None => {
            let p = port(ports)?;
            (p, p)
        }
    };
    if last < first {
        return Err(TargetError::ReversedRange {
            item: item.to_string(),
            first,
            last,
        });
    }
    let count = usize::from(last - first) + 1;
    if count > MAX_RANGE_PORTS {
        return Err(TargetError::RangeTooLong {
            item: item.to_string(),
            count,
        });
    }
    Ok((first..=last).map(|p| SocketAddr::new(ip, p)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn addrs(list: &[&str]) -> Vec<SocketAddr> {
        list.iter().map(|s| s.parse().unwrap()).collect()
    }

    #[test]
    fn single_range_broadcast_and_v6() {
        assert_eq!(
            parse_targets("127.0.0.1:7000").unwrap(),
            addrs(&["127.0.0.1:7000"])
        );
        let r = parse_targets("127.0.0.1:7000-7017").unwrap();
        assert_eq!(r.len(), 18);
        assert_eq!(r[0], "127.0.0.1:7000".parse().unwrap());
        assert_eq!(r[17], "127.0.0.1:7017".parse().unwrap());
        assert_eq!(
            parse_targets("255.255.255.255:7000").unwrap(),
            addrs(&["255.255.255.255:7000"])
        );
        assert_eq!(
            parse_targets("[::1]:7000-7001").unwrap(),
            addrs(&["[::1]:7000", "[::1]:7001"])
        );
    }

    #[test]
    fn lists_keep_order_and_drop_duplicates() {
        let r = parse_targets(" 10.0.0.2:7000, 10.0.0.1:7000-7001  10.0.0.2:7000 ").unwrap();
        assert_eq!(
            r,
            addrs(&["10.0.0.2:7000", "10.0.0.1:7000", "10.0.0.1:7001"])
        );
    }

    #[test]
    fn errors_name_the_item() {
        assert_eq!(parse_targets(" , "), Err(TargetError::Empty));
        assert!(matches!(
            parse_targets("127.0.0.1"),
            Err(TargetError::Syntax(_))
        ));
        assert!(matches!(
            parse_targets("::1:7000"),
            Err(TargetError::Syntax(_))
        ));
        assert!(matches!(
            parse_targets(":7000"),
            Err(TargetError::Syntax(_))
        ));
        assert!(matches!(
            parse_targets("[::1:7000"),
            Err(TargetError::Syntax(_))
        ));
        let e = parse_targets("snake.local:7000").unwrap_err();
        assert!(matches!(&e, TargetError::BadIp { ip, .. } if ip == "snake.local"));
        assert!(e.to_string().contains("snake.local:7000"));
        for bad in ["1.2.3.4:0", "1.2.3.4:65536", "1.2.3.4:x", "1.2.3.4:7000-"] {
            assert!(
                matches!(parse_targets(bad), Err(TargetError::BadPort { .. })),
                "{bad}"
            );
        }
        assert!(matches!(
            parse_targets("1.2.3.4:7010-7000"),
            Err(TargetError::ReversedRange {
                first: 7010,
                last: 7000,
                ..
            })
        ));
        assert!(matches!(
            parse_targets("1.2.3.4:1-65535"),
            Err(TargetError::RangeTooLong { count: 65535, .. })
        ));
    }
}
