//! The datagram decoder: never panics, and whatever decodes re-encodes to the very
//! same bytes (the encoding is canonical, docs/protocol.md).
#![no_main]
use libfuzzer_sys::fuzz_target;
use snaked::protocol::{MAX_DATAGRAM, decode, encode};

fuzz_target!(|data: &[u8]| {
    check(data);
    // The same bytes with a valid trailer, so that the payload parsers behind the
    // checksum are reached. Protocol v1 only: its trailer is a CRC-32 of the rest.
    if let Some(body_len) = data.len().checked_sub(4) {
        let mut d = data.to_vec();
        let crc = crc32fast::hash(&d[..body_len]);
        d[body_len..].copy_from_slice(&crc.to_le_bytes());
        check(&d);
    }
});

fn check(datagram: &[u8]) {
    let Ok((header, msg)) = decode(datagram) else {
        return;
    };
    assert_eq!(header.msg_type, msg.msg_type());
    let mut buf = [0u8; MAX_DATAGRAM];
    let n = encode(header.session, header.seq, &msg, &mut buf).expect("decoded re-encodes");
    assert_eq!(&buf[..n], datagram, "not canonical: {msg:?}");
}
