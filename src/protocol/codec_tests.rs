use super::*;

const K: Key = Key::from_bytes([9; 32]);
fn route(session: u32, seq: u64, unit: u16) -> Route {
    Route { session, seq, unit }
}

#[test]
fn header_fields_sit_at_their_offsets() {
    let mut buf = [0u8; MAX_DATAGRAM];
    let fb = Message::Feedback(Feedback::default());
    let n = encode(
        route(0x0102_0304, 0x0a0b_0c0d_0e0f_1011, 0x1213),
        &fb,
        &K,
        &mut buf,
    )
    .unwrap();
    assert_eq!(n, FRAME_OVERHEAD + FEEDBACK_LEN);
    assert_eq!(&buf[..4], b"SN\x02\x09");
    assert_eq!(&buf[4..8], &[4, 3, 2, 1]);
    assert_eq!(
        &buf[8..16],
        &[0x11, 0x10, 0x0f, 0x0e, 0x0d, 0x0c, 0x0b, 0x0a]
    );
    assert_eq!(&buf[16..18], &[0x13, 0x12]);
    assert_eq!(&buf[18..20], &[FEEDBACK_LEN as u8, 0]);
    assert_eq!(&buf[n - TAG_LEN..n], &K.tag(&buf[..n - TAG_LEN]));
    let (h, back) = decode(&buf[..n], |_| K).unwrap();
    assert_eq!(
        (h.session, h.seq, h.unit, back),
        (0x0102_0304, 0x0a0b_0c0d_0e0f_1011, 0x1213, fb)
    );
}

#[test]
fn tag_covers_every_byte_and_the_key() {
    let mut buf = [0u8; MAX_DATAGRAM];
    let n = encode(
        route(1, 2, 0),
        &Message::Command(Command::position(0.3)),
        &K,
        &mut buf,
    )
    .unwrap();
    for i in 4..n {
        let mut d = buf;
        d[i] ^= 0x80;
        let e = decode(&d[..n], |_| K).unwrap_err();
        // The tag catches it, or the header already does (type, length).
        assert!(
            matches!(
                e,
                DecodeError::BadTag
                    | DecodeError::BadLength
                    | DecodeError::Truncated
                    | DecodeError::UnknownType(_)
            ),
            "byte {i}: {e:?}"
        );
    }
    assert_eq!(
        decode(&buf[..n], |_| Key::OPEN).unwrap_err(),
        DecodeError::BadTag
    );
}

#[test]
fn frames_split_a_bundle() {
    let mut buf = [0u8; MAX_DATAGRAM];
    let mut len = 0;
    for unit in 0..3u16 {
        let m = Message::Command(Command::position(f64::from(unit)));
        len += encode(route(5, 7, unit), &m, &K, &mut buf[len..]).unwrap();
    }
    let units: Vec<u16> = Frames::new(&buf[..len])
        .map(|f| {
            let (h, frame) = f.unwrap();
            open(frame, &K).unwrap();
            h.unit
        })
        .collect();
    assert_eq!(units, [0, 1, 2]);
    let cut: Vec<_> = Frames::new(&buf[..len - 1]).collect();
    assert_eq!(cut.len(), 3);
    assert_eq!(cut[2].unwrap_err(), DecodeError::Truncated);
}

#[test]
fn version_1_is_told_apart() {
    let mut v1 = [0u8; 32];
    v1[..4].copy_from_slice(b"SN\x01\x08");
    assert_eq!(peek(&v1).unwrap_err(), DecodeError::WrongVersion(1));
    assert_eq!(peek(&v1[..20]).unwrap_err(), DecodeError::WrongVersion(1));
}
