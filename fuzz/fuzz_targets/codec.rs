//! The frame decoder, protocol v2: never panics, and whatever opens re-encodes to the
//! very same bytes (the encoding is canonical, docs/protocol.md). Frames are tagged
//! under a fixed key; every input is also tried with each of its frames re-tagged under
//! that key, so that the payload parsers behind the tag are reached.
#![no_main]
use libfuzzer_sys::fuzz_target;
use snaked::protocol::{Frames, Key, MAX_DATAGRAM, Route, TAG_LEN, encode, open, peek};

/// The key the seeds are tagged with (`cargo run --example fuzz_seeds`).
const KEY: Key = Key::from_bytes([0x5a; 32]);

fuzz_target!(|data: &[u8]| {
    check(data);
    let mut d = data.to_vec();
    let mut at = 0;
    while let Ok((_, len)) = peek(&d[at..]) {
        let body = at + len - TAG_LEN;
        let tag = KEY.tag(&d[at..body]);
        d[body..at + len].copy_from_slice(&tag);
        at += len;
    }
    check(&d);
});

fn check(datagram: &[u8]) {
    for frame in Frames::new(datagram) {
        let Ok((h, frame)) = frame else { return };
        let Ok(msg) = open(frame, &KEY) else { continue };
        assert_eq!(h.msg_type, msg.msg_type());
        let mut buf = [0u8; MAX_DATAGRAM];
        let route = Route {
            session: h.session,
            seq: h.seq,
            unit: h.unit,
        };
        let n = encode(route, &msg, &KEY, &mut buf).expect("decoded re-encodes");
        assert_eq!(&buf[..n], frame, "not canonical: {msg:?}");
    }
}
