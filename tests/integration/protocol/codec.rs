//! Codec tests for protocol v2: round trips of every message (bit-exact, NaN
//! included), every decode error from a crafted frame, robustness against corruption,
//! and the tag: a frame opens only under the key it was tagged with. Layouts:
//! docs/protocol.md.
use proptest::prelude::*;
use snaked::protocol::{
    AcquireReply, Announce, Command, ControlStrategy, DecodeError, EncodeError, Feedback, Frames,
    Key, LookupFilter, MAX_DATAGRAM, Message, MsgType, Name, Route, Settings, decode, encode,
};

// ---- helpers -------------------------------------------------------------------

/// The key of these tests.
const K: Key = Key::from_bytes([0x42; 32]);
const NONCE: [u8; 16] = [0x33; 16];

fn route(session: u32, seq: u64) -> Route {
    Route {
        session,
        seq,
        unit: 0,
    }
}

/// A frame with a correct tag (under `K`) around an arbitrary header and payload.
fn frame_with(version: u8, msg_type: u8, payload: &[u8]) -> Vec<u8> {
    let mut d = Vec::new();
    d.extend_from_slice(b"SN");
    d.push(version);
    d.push(msg_type);
    d.extend_from_slice(&7u32.to_le_bytes());
    d.extend_from_slice(&9u64.to_le_bytes());
    d.extend_from_slice(&0u16.to_le_bytes());
    d.extend_from_slice(&(payload.len() as u16).to_le_bytes());
    d.extend_from_slice(payload);
    let tag = K.tag(&d);
    d.extend_from_slice(&tag);
    d
}

fn frame(msg_type: u8, payload: &[u8]) -> Vec<u8> {
    frame_with(2, msg_type, payload)
}

fn enc(msg: &Message) -> Vec<u8> {
    let mut buf = [0u8; MAX_DATAGRAM];
    let n = encode(route(7, 9), msg, &K, &mut buf).expect("encodable");
    buf[..n].to_vec()
}

fn dec(d: &[u8]) -> Result<(snaked::protocol::Header, Message), DecodeError> {
    decode(d, |_| K)
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
    dec(d).expect_err("datagram must be rejected")
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
        any::<u64>(),
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
        (
            any::<[u8; 6]>(),
            name(),
            name(),
            any::<u32>(),
            any::<bool>()
        )
            .prop_map(
                |(mac, family, name, firmware, owned)| Message::Announce(Announce {
                    mac,
                    family,
                    name,
                    firmware,
                    owned,
                })
            ),
        any::<[u8; 16]>().prop_map(Message::Acquire),
        (any::<bool>(), any::<[u8; 16]>()).prop_map(|(granted, module_nonce)| {
            Message::AcquireReply(AcquireReply {
                granted,
                module_nonce,
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
    fn round_trip_every_message(
        msg in message(),
        session in any::<u32>(),
        seq in any::<u64>(),
        unit in any::<u16>(),
        key in any::<[u8; 32]>(),
    ) {
        let key = Key::from_bytes(key);
        let mut buf = [0u8; MAX_DATAGRAM];
        let n = encode(Route { session, seq, unit }, &msg, &key, &mut buf).expect("encodable");
        prop_assert!(n <= MAX_DATAGRAM);
        let (h, back) = decode(&buf[..n], |_| key).expect("own datagram decodes");
        prop_assert_eq!(h.msg_type, msg.msg_type());
        prop_assert_eq!((h.session, h.seq, h.unit), (session, seq, unit));
        prop_assert!(same(&msg, &back), "{:?} != {:?}", msg, back);
        // Under any other key it does not open.
        prop_assert_eq!(decode(&buf[..n], |_| K).unwrap_err(), DecodeError::BadTag);
    }

    #[test]
    fn any_byte_flip_is_rejected(msg in message(), pos in any::<prop::sample::Index>(), x in 1u8..=255) {
        let mut d = enc(&msg);
        let i = pos.index(d.len());
        d[i] ^= x;
        prop_assert!(dec(&d).is_err(), "flip at {} accepted", i);
    }

    #[test]
    fn any_truncation_or_extension_is_rejected(
        msg in message(),
        cut in any::<prop::sample::Index>(),
        extra in prop::collection::vec(any::<u8>(), 1..8),
    ) {
        let d = enc(&msg);
        prop_assert!(dec(&d[..cut.index(d.len())]).is_err());
        let mut longer = d.clone();
        longer.extend_from_slice(&extra);
        prop_assert_eq!(dec(&longer).unwrap_err(), DecodeError::BadLength);
    }

    #[test]
    fn random_bytes_never_panic(d in prop::collection::vec(any::<u8>(), 0..1500)) {
        let _ = dec(&d);
        for f in Frames::new(&d) {
            let _ = f.map(|(_, frame)| snaked::protocol::open(frame, &K));
        }
    }

    /// Correctly framed datagrams with random payloads exercise every payload parser;
    /// whatever decodes must re-encode to the very same bytes (canonical encoding).
    #[test]
    fn framed_random_payloads_are_canonical(
        msg_type in 0u8..=10,
        payload in prop_oneof![Just(0usize), Just(12), Just(16), Just(20), Just(64), Just(78), 0usize..120]
            .prop_flat_map(|n| prop::collection::vec(any::<u8>(), n)),
    ) {
        let d = frame(msg_type, &payload);
        if let Ok((h, msg)) = dec(&d) {
            let mut buf = [0u8; MAX_DATAGRAM];
            let r = Route { session: h.session, seq: h.seq, unit: h.unit };
            let n = encode(r, &msg, &K, &mut buf).expect("decoded message re-encodes");
            prop_assert_eq!(&buf[..n], &d[..]);
        }
    }
}

// ---- fixed vectors and crafted errors ------------------------------------------

/// The byte layout of docs/protocol.md, written out: a Command tagged under the key
/// 00 01 02 … 1f.
#[test]
fn command_golden_bytes() {
    let mut buf = [0u8; 64];
    let cmd = Command {
        position_rad: 1.0,
        velocity_rad_s: f32::NAN,
        torque_nm: -2.5,
    };
    let key = Key::from_bytes(std::array::from_fn(|i| i as u8));
    let r = Route {
        session: 0x0403_0201,
        seq: 5,
        unit: 0,
    };
    let n = encode(r, &Message::Command(cmd), &key, &mut buf).unwrap();
    let mut want = vec![
        b'S', b'N', 2, 8, // magic, version, type = Command
        1, 2, 3, 4, // session
        5, 0, 0, 0, 0, 0, 0, 0, // seq
        0, 0, // unit
        12, 0, // payload length
        0x00, 0x00, 0x80, 0x3f, // 1.0
        0x00, 0x00, 0xc0, 0x7f, // NaN (quiet)
        0x00, 0x00, 0x20, 0xc0, // -2.5
    ];
    let tag = key.tag(&want);
    assert_eq!(hex(&tag), GOLDEN_TAG, "the value docs/protocol.md quotes");
    want.extend_from_slice(&tag);
    assert_eq!(&buf[..n], &want[..]);
    assert_eq!(n, 48);
}

const GOLDEN_TAG: &str = "54 85 d4 e3 8e 59 b8 77 c2 38 ba 7c 5d 5c 18 37";

fn hex(b: &[u8]) -> String {
    b.iter()
        .map(|x| format!("{x:02x}"))
        .collect::<Vec<_>>()
        .join(" ")
}

#[test]
fn sizes_of_fixed_messages() {
    let fb = Message::Feedback(Feedback::default());
    assert_eq!(enc(&fb).len(), 100);
    assert_eq!(enc(&Message::Acquire(NONCE)).len(), 52);
    assert_eq!(enc(&Message::Release).len(), 36);
    assert_eq!(enc(&Message::Settings(Settings::default())).len(), 48);
    assert_eq!(enc(&Message::Command(Command::LIMP)).len(), 48);
}

#[test]
fn truncated() {
    assert_eq!(err(&[]), DecodeError::Truncated);
    assert_eq!(err(&enc(&Message::Release)[..35]), DecodeError::Truncated);
    let d = enc(&Message::Command(Command::LIMP));
    assert_eq!(err(&d[..d.len() - 1]), DecodeError::Truncated);
}

#[test]
fn bad_magic() {
    let mut d = enc(&Message::Acquire(NONCE));
    d[0] = b'X';
    assert_eq!(err(&d), DecodeError::BadMagic);
}

#[test]
fn wrong_version() {
    assert_eq!(err(&frame_with(3, 3, &[])), DecodeError::WrongVersion(3));
    // A v1 datagram (16-byte header, CRC trailer) is told apart, short or not.
    assert_eq!(
        err(&frame_with(1, 8, &[0; 12])),
        DecodeError::WrongVersion(1)
    );
    assert_eq!(
        err(b"SN\x01\x03\x01\x00\x00\x00"),
        DecodeError::WrongVersion(1)
    );
}

#[test]
fn unknown_type() {
    assert_eq!(err(&frame(0, &[])), DecodeError::UnknownType(0));
    assert_eq!(err(&frame(10, &[])), DecodeError::UnknownType(10));
}

#[test]
fn bad_length() {
    // Trailing byte after the tag.
    let mut d = enc(&Message::Acquire(NONCE));
    d.push(0);
    assert_eq!(err(&d), DecodeError::BadLength);
    // Payload size that does not fit the message type.
    assert_eq!(err(&frame(8, &[0; 8])), DecodeError::BadLength);
    assert_eq!(err(&frame(3, &[0; 1])), DecodeError::BadLength);
    // Declared payload larger than any datagram.
    let mut d = frame(5, &[]);
    d[18..20].copy_from_slice(&2000u16.to_le_bytes());
    assert_eq!(err(&d), DecodeError::BadLength);
}

#[test]
fn bad_tag() {
    let mut d = enc(&Message::Command(Command::position(0.5)));
    let last = d.len() - 1;
    d[last] ^= 0x01;
    assert_eq!(err(&d), DecodeError::BadTag);
    // Another key: another session, another network.
    let d = enc(&Message::Command(Command::position(0.5)));
    assert_eq!(decode(&d, |_| Key::OPEN).unwrap_err(), DecodeError::BadTag);
}

fn malformed(d: &[u8], why: &str) {
    match dec(d) {
        Err(DecodeError::Malformed(m)) => assert!(m.contains(why), "{m:?} lacks {why:?}"),
        other => panic!("expected Malformed({why}), got {other:?}"),
    }
}

#[test]
fn malformed_header_and_fixed_payloads() {
    // AcquireReply: granted flag 2, then non-zero reserved.
    let mut r = [0u8; 20];
    r[0] = 2;
    malformed(&frame(4, &r), "granted");
    r[0] = 1;
    r[2] = 9;
    malformed(&frame(4, &r), "reserved");
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
        owned: true,
    };
    enc(&Message::Announce(a))[20..20 + 78].to_vec()
}

#[test]
fn malformed_announce() {
    assert!(dec(&frame(2, &announce_payload())).is_ok());
    let mut p = announce_payload();
    p[6] = 2; // an unknown flag
    malformed(&frame(2, &p), "flags");
    let mut p = announce_payload();
    p[7] = 1; // reserved after the flags
    malformed(&frame(2, &p), "reserved");
    let mut p = announce_payload();
    p[13] = 33; // name length
    malformed(&frame(2, &p), "too long");
    let mut p = announce_payload();
    p[46 + 5] = b'x'; // a byte after the name's 3 bytes
    malformed(&frame(2, &p), "padding");
    let mut p = announce_payload();
    p[46] = 0xff; // first byte of the name
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
    assert!(dec(&lookup(2, 0, 2, b"\x01a\x02bc")).is_ok());
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
    let mut small = [0u8; 51];
    assert_eq!(
        encode(route(1, 1), &Message::Acquire(NONCE), &K, &mut small),
        Err(EncodeError::BufferTooSmall)
    );
    let long = Name::new(&"n".repeat(32)).unwrap();
    let too_many = Message::Lookup(LookupFilter::Names(vec![long; 50]));
    let mut buf = [0u8; 4096];
    assert_eq!(
        encode(route(0, 0), &too_many, &K, &mut buf),
        Err(EncodeError::TooLarge)
    );
    let inf = Message::Command(Command {
        torque_nm: f32::NEG_INFINITY,
        ..Command::LIMP
    });
    assert!(matches!(
        encode(route(1, 1), &inf, &K, &mut buf),
        Err(EncodeError::Invalid(_))
    ));
    let nan_settings = Settings {
        command_lifetime_s: f32::NAN,
        ..Settings::default()
    };
    assert!(matches!(
        encode(
            route(1, 1),
            &Message::SettingsAck(nan_settings),
            &K,
            &mut buf
        ),
        Err(EncodeError::Invalid(_))
    ));
}

#[test]
fn header_fields_survive() {
    let d = enc(&Message::Release);
    let (h, m) = dec(&d).unwrap();
    assert_eq!((h.msg_type, h.session, h.seq), (MsgType::Release, 7, 9));
    assert_eq!(m, Message::Release);
}

#[test]
fn handshake_types_use_the_network_key() {
    let net: Vec<MsgType> = [1, 2, 3, 4, 5, 6, 7, 8, 9]
        .into_iter()
        .map(|t| dec(&frame(t, &[])).map(|(h, _)| h.msg_type))
        .filter_map(|r| r.ok().or(None))
        .collect();
    assert!(net.contains(&MsgType::Release));
    assert!(MsgType::Lookup.uses_network_key() && MsgType::AcquireReply.uses_network_key());
    assert!(!MsgType::Command.uses_network_key() && !MsgType::Feedback.uses_network_key());
}
