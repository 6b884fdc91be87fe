//! Codec tests for protocol v1: round trips of every message (bit-exact, NaN
//! included), every decode error from a crafted datagram, and robustness against
//! corruption. Layouts: docs/protocol.md.
use proptest::prelude::*;
use snaked::protocol::{
    AcquireReply, Announce, Command, ControlStrategy, DecodeError, EncodeError, Feedback,
    LookupFilter, MAX_DATAGRAM, Message, MsgType, Name, Settings, decode, encode,
};

// ---- helpers -------------------------------------------------------------------

/// A datagram with a correct checksum around an arbitrary header and payload.
fn frame_with(version: u8, msg_type: u8, reserved: u16, payload: &[u8]) -> Vec<u8> {
    let mut d = Vec::new();
    d.extend_from_slice(b"SN");
    d.push(version);
    d.push(msg_type);
    d.extend_from_slice(&7u32.to_le_bytes());
    d.extend_from_slice(&9u32.to_le_bytes());
    d.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    d.extend_from_slice(&reserved.to_le_bytes());
    d.extend_from_slice(payload);
    let crc = crc32fast::hash(&d);
    d.extend_from_slice(&crc.to_le_bytes());
    d
}

fn frame(msg_type: u8, payload: &[u8]) -> Vec<u8> {
    frame_with(1, msg_type, 0, payload)
}

fn enc(msg: &Message) -> Vec<u8> {
    let mut buf = [0u8; MAX_DATAGRAM];
    let n = encode(7, 9, msg, &mut buf).expect("encodable");
    buf[..n].to_vec()
}

fn f32_bits_eq(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits()
}

fn settings_eq(a: &Settings, b: &Settings) -> bool {
    f32_bits_eq(a.feedback_rate_hz, b.feedback_rate_hz)
        && f32_bits_eq(a.command_lifetime_s, b.command_lifetime_s)
        && a.strategy == b.strategy
}

/// Equality with floats compared by bit pattern, so NaN payloads must survive.
fn same(a: &Message, b: &Message) -> bool {
    match (a, b) {
        (Message::Settings(x), Message::Settings(y))
        | (Message::SettingsAck(x), Message::SettingsAck(y)) => settings_eq(x, y),
        (Message::Command(x), Message::Command(y)) => {
            f32_bits_eq(x.position_rad, y.position_rad)
                && f32_bits_eq(x.velocity_rad_s, y.velocity_rad_s)
                && f32_bits_eq(x.torque_nm, y.torque_nm)
        }
        (Message::Feedback(x), Message::Feedback(y)) => {
            let fx = feedback_floats(x);
            let fy = feedback_floats(y);
            x.module_time_us == y.module_time_us
                && x.last_command_seq == y.last_command_seq
                && fx.iter().zip(&fy).all(|(p, q)| f32_bits_eq(*p, *q))
        }
        _ => a == b,
    }
}

fn feedback_floats(f: &Feedback) -> [f32; 12] {
    let [ax, ay, az] = f.accel_m_s2;
    let [gx, gy, gz] = f.gyro_rad_s;
    [
        f.position_rad,
        f.velocity_rad_s,
        f.torque_nm,
        f.deflection_rad,
        ax,
        ay,
        az,
        gx,
        gy,
        gz,
        f.temperature_c,
        f.voltage_v,
    ]
}

fn err(d: &[u8]) -> DecodeError {
    decode(d).expect_err("datagram must be rejected")
}

// ---- strategies ----------------------------------------------------------------

fn name() -> impl Strategy<Value = Name> {
    prop::collection::vec(any::<char>(), 0..12).prop_filter_map("fits", |cs| {
        Name::new(&cs.into_iter().collect::<String>()).ok()
    })
}

fn any_f32() -> impl Strategy<Value = f32> {
    any::<u32>().prop_map(f32::from_bits)
}

/// Any bit pattern a set-point may take: finite or NaN (any payload), never infinite.
fn set_point() -> impl Strategy<Value = f32> {
    any_f32().prop_filter("not infinite", |v| !v.is_infinite())
}

fn settings() -> impl Strategy<Value = Settings> {
    let finite = || any_f32().prop_filter("finite", |v| v.is_finite());
    let strategy = prop_oneof![Just(ControlStrategy::Off), Just(ControlStrategy::Cascaded)];
    (finite(), finite(), strategy).prop_map(|(r, l, s)| Settings {
        feedback_rate_hz: r,
        command_lifetime_s: l,
        strategy: s,
    })
}

fn feedback() -> impl Strategy<Value = Feedback> {
    (
        any::<u64>(),
        any::<u32>(),
        prop::array::uniform12(any_f32()),
    )
        .prop_map(|(t, seq, v)| Feedback {
            module_time_us: t,
            last_command_seq: seq,
            position_rad: v[0],
            velocity_rad_s: v[1],
            torque_nm: v[2],
            deflection_rad: v[3],
            accel_m_s2: [v[4], v[5], v[6]],
            gyro_rad_s: [v[7], v[8], v[9]],
            temperature_c: v[10],
            voltage_v: v[11],
        })
}

fn filter() -> impl Strategy<Value = LookupFilter> {
    prop_oneof![
        Just(LookupFilter::All),
        name().prop_map(LookupFilter::Family),
        prop::collection::vec(name(), 0..40).prop_map(LookupFilter::Names),
        prop::collection::vec(any::<[u8; 6]>(), 0..200).prop_map(LookupFilter::Macs),
    ]
}

fn message() -> impl Strategy<Value = Message> {
    prop_oneof![
        filter().prop_map(Message::Lookup),
        (any::<[u8; 6]>(), name(), name(), any::<u32>(), any::<u32>()).prop_map(
            |(mac, family, name, firmware, owner_session)| Message::Announce(Announce {
                mac,
                family,
                name,
                firmware,
                owner_session,
            })
        ),
        Just(Message::Acquire),
        (any::<bool>(), any::<u32>()).prop_map(|(granted, owner_session)| {
            Message::AcquireReply(AcquireReply {
                granted,
                owner_session,
            })
        }),
        Just(Message::Release),
        settings().prop_map(Message::Settings),
        settings().prop_map(Message::SettingsAck),
        (set_point(), set_point(), set_point()).prop_map(|(p, v, t)| Message::Command(Command {
            position_rad: p,
            velocity_rad_s: v,
            torque_nm: t,
        })),
        feedback().prop_map(Message::Feedback),
    ]
}

// ---- properties ----------------------------------------------------------------

proptest! {
    #[test]
    fn round_trip_every_message(msg in message(), session in any::<u32>(), seq in any::<u32>()) {
        let mut buf = [0u8; MAX_DATAGRAM];
        let n = encode(session, seq, &msg, &mut buf).expect("encodable");
        prop_assert!(n <= MAX_DATAGRAM);
        let (h, back) = decode(&buf[..n]).expect("own datagram decodes");
        prop_assert_eq!(h.msg_type, msg.msg_type());
        prop_assert_eq!(h.session, session);
        prop_assert_eq!(h.seq, seq);
        prop_assert!(same(&msg, &back), "{:?} != {:?}", msg, back);
    }

    #[test]
    fn any_byte_flip_is_rejected(msg in message(), pos in any::<prop::sample::Index>(), x in 1u8..=255) {
        let mut d = enc(&msg);
        let i = pos.index(d.len());
        d[i] ^= x;
        prop_assert!(decode(&d).is_err(), "flip at {} accepted", i);
    }

    #[test]
    fn any_truncation_or_extension_is_rejected(
        msg in message(),
        cut in any::<prop::sample::Index>(),
        extra in prop::collection::vec(any::<u8>(), 1..8),
    ) {
        let d = enc(&msg);
        prop_assert!(decode(&d[..cut.index(d.len())]).is_err());
        let mut longer = d.clone();
        longer.extend_from_slice(&extra);
        prop_assert_eq!(decode(&longer).unwrap_err(), DecodeError::BadLength);
    }

    #[test]
    fn random_bytes_never_panic(d in prop::collection::vec(any::<u8>(), 0..1500)) {
        let _ = decode(&d);
    }

    /// Correctly framed datagrams with random payloads exercise every payload parser;
    /// whatever decodes must re-encode to the very same bytes (canonical encoding).
    #[test]
    fn framed_random_payloads_are_canonical(
        msg_type in 0u8..=10,
        payload in prop_oneof![Just(0usize), Just(8), Just(12), Just(60), Just(82), 0usize..120]
            .prop_flat_map(|n| prop::collection::vec(any::<u8>(), n)),
    ) {
        let d = frame(msg_type, &payload);
        if let Ok((h, msg)) = decode(&d) {
            let mut buf = [0u8; MAX_DATAGRAM];
            let n = encode(h.session, h.seq, &msg, &mut buf).expect("decoded message re-encodes");
            prop_assert_eq!(&buf[..n], &d[..]);
        }
    }
}

// ---- fixed vectors and crafted errors ------------------------------------------

/// The byte layout of docs/protocol.md, written out: a Command.
#[test]
fn command_golden_bytes() {
    let mut buf = [0u8; 64];
    let cmd = Command {
        position_rad: 1.0,
        velocity_rad_s: f32::NAN,
        torque_nm: -2.5,
    };
    let n = encode(0x0403_0201, 5, &Message::Command(cmd), &mut buf).unwrap();
    let mut want = vec![
        b'S', b'N', 1, 8, // magic, version, type = Command
        1, 2, 3, 4, // session
        5, 0, 0, 0, // seq
        12, 0, 0, 0, // payload length, reserved
        0x00, 0x00, 0x80, 0x3f, // 1.0
        0x00, 0x00, 0xc0, 0x7f, // NaN (quiet)
        0x00, 0x00, 0x20, 0xc0, // -2.5
    ];
    let crc = crc32fast::hash(&want);
    assert_eq!(crc, 0x5B7D_667E, "the value docs/protocol.md quotes");
    want.extend_from_slice(&crc.to_le_bytes());
    assert_eq!(&buf[..n], &want[..]);
    assert_eq!(n, 32);
}

#[test]
fn sizes_of_fixed_messages() {
    let fb = Message::Feedback(Feedback::default());
    assert_eq!(enc(&fb).len(), 80);
    assert_eq!(enc(&Message::Acquire).len(), 20);
    assert_eq!(enc(&Message::Settings(Settings::default())).len(), 32);
}

#[test]
fn truncated() {
    assert_eq!(err(&[]), DecodeError::Truncated);
    assert_eq!(err(&enc(&Message::Acquire)[..19]), DecodeError::Truncated);
    let d = enc(&Message::Command(Command::LIMP));
    assert_eq!(err(&d[..d.len() - 1]), DecodeError::Truncated);
}

#[test]
fn bad_magic() {
    let mut d = enc(&Message::Acquire);
    d[0] = b'X';
    assert_eq!(err(&d), DecodeError::BadMagic);
}

#[test]
fn wrong_version() {
    assert_eq!(err(&frame_with(2, 3, 0, &[])), DecodeError::WrongVersion(2));
}

#[test]
fn unknown_type() {
    assert_eq!(err(&frame(0, &[])), DecodeError::UnknownType(0));
    assert_eq!(err(&frame(10, &[])), DecodeError::UnknownType(10));
}

#[test]
fn bad_length() {
    // Trailing byte after the checksum.
    let mut d = enc(&Message::Acquire);
    d.push(0);
    assert_eq!(err(&d), DecodeError::BadLength);
    // Payload size that does not fit the message type.
    assert_eq!(err(&frame(8, &[0; 8])), DecodeError::BadLength);
    assert_eq!(err(&frame(3, &[0; 1])), DecodeError::BadLength);
    // Declared payload larger than any datagram.
    let mut d = frame(3, &[]);
    d[12..14].copy_from_slice(&2000u16.to_le_bytes());
    assert_eq!(err(&d), DecodeError::BadLength);
}

#[test]
fn bad_checksum() {
    let mut d = enc(&Message::Command(Command::position(0.5)));
    let last = d.len() - 1;
    d[last] ^= 0x01;
    assert_eq!(err(&d), DecodeError::BadChecksum);
}

fn malformed(d: &[u8], why: &str) {
    match decode(d) {
        Err(DecodeError::Malformed(m)) => assert!(m.contains(why), "{m:?} lacks {why:?}"),
        other => panic!("expected Malformed({why}), got {other:?}"),
    }
}

#[test]
fn malformed_header_and_fixed_payloads() {
    malformed(&frame_with(1, 3, 1, &[]), "reserved header");
    // AcquireReply: granted flag 2, then non-zero reserved.
    malformed(&frame(4, &[2, 0, 0, 0, 1, 0, 0, 0]), "granted");
    malformed(&frame(4, &[1, 0, 9, 0, 1, 0, 0, 0]), "reserved");
    // Settings: strategy 2; reserved; NaN rate.
    let mut s = [0u8; 12];
    s[0..4].copy_from_slice(&100f32.to_le_bytes());
    s[4..8].copy_from_slice(&0.05f32.to_le_bytes());
    s[8] = 2;
    malformed(&frame(6, &s), "strategy");
    s[8] = 1;
    s[11] = 1;
    malformed(&frame(7, &s), "reserved");
    s[11] = 0;
    s[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
    malformed(&frame(6, &s), "not finite");
    // Command with an infinite set-point.
    let mut c = [0u8; 12];
    c[4..8].copy_from_slice(&f32::INFINITY.to_le_bytes());
    malformed(&frame(8, &c), "infinite");
}

fn announce_payload() -> Vec<u8> {
    let a = Announce {
        mac: [1, 2, 3, 4, 5, 6],
        family: Name::new("SEA").unwrap(),
        name: Name::new("m01").unwrap(),
        firmware: 3,
        owner_session: 0,
    };
    enc(&Message::Announce(a))[16..16 + 82].to_vec()
}

#[test]
fn malformed_announce() {
    assert!(decode(&frame(2, &announce_payload())).is_ok());
    let mut p = announce_payload();
    p[6] = 1; // reserved after the MAC
    malformed(&frame(2, &p), "reserved");
    let mut p = announce_payload();
    p[17] = 33; // name length
    malformed(&frame(2, &p), "too long");
    let mut p = announce_payload();
    p[50 + 5] = b'x'; // a byte after the name's 3 bytes
    malformed(&frame(2, &p), "padding");
    let mut p = announce_payload();
    p[50] = 0xff; // first byte of the name
    malformed(&frame(2, &p), "UTF-8");
}

#[test]
fn malformed_lookup() {
    let lookup = |kind: u8, reserved: u8, count: u16, rest: &[u8]| {
        let mut p = vec![kind, reserved];
        p.extend_from_slice(&count.to_le_bytes());
        p.extend_from_slice(rest);
        frame(1, &p)
    };
    assert!(decode(&lookup(2, 0, 2, b"\x01a\x02bc")).is_ok());
    malformed(&frame(1, &[0, 0]), "shorter");
    malformed(&lookup(4, 0, 0, &[]), "filter kind");
    malformed(&lookup(0, 1, 0, &[]), "reserved");
    malformed(&lookup(0, 0, 1, &[]), "count");
    malformed(&lookup(1, 0, 2, b"\x01a\x01b"), "count");
    malformed(&lookup(2, 0, 5, b"\x01a\x01b"), "exceeds");
    malformed(&lookup(2, 0, 2, b"\x01a\x05bc"), "ends inside");
    malformed(&lookup(3, 0, 3, &[0; 12]), "exceeds");
    malformed(&lookup(3, 0, 1, &[0; 8]), "trailing");
    malformed(&lookup(2, 0, 1, b"\x01a\x00"), "trailing");
    let mut long = vec![33u8];
    long.extend_from_slice(&[b'a'; 33]);
    malformed(&lookup(1, 0, 1, &long), "too long");
    malformed(&lookup(2, 0, 1, b"\x02\xc3\x28"), "UTF-8");
}

#[test]
fn encode_errors() {
    let mut small = [0u8; 19];
    assert_eq!(
        encode(1, 1, &Message::Acquire, &mut small),
        Err(EncodeError::BufferTooSmall)
    );
    let long = Name::new(&"n".repeat(32)).unwrap();
    let too_many = Message::Lookup(LookupFilter::Names(vec![long; 50]));
    let mut buf = [0u8; 4096];
    assert_eq!(
        encode(0, 0, &too_many, &mut buf),
        Err(EncodeError::TooLarge)
    );
    let inf = Message::Command(Command {
        torque_nm: f32::NEG_INFINITY,
        ..Command::LIMP
    });
    assert!(matches!(
        encode(1, 1, &inf, &mut buf),
        Err(EncodeError::Invalid(_))
    ));
    let nan_settings = Settings {
        command_lifetime_s: f32::NAN,
        ..Settings::default()
    };
    assert!(matches!(
        encode(1, 1, &Message::SettingsAck(nan_settings), &mut buf),
        Err(EncodeError::Invalid(_))
    ));
}

#[test]
fn header_fields_survive() {
    let d = enc(&Message::Release);
    let (h, m) = decode(&d).unwrap();
    assert_eq!((h.msg_type, h.session, h.seq), (MsgType::Release, 7, 9));
    assert_eq!(m, Message::Release);
}
