//! Writes the codec fuzz target's seeds (`fuzz/seeds/codec/`): one valid frame of every
//! message type, a gateway bundle, and a v1 datagram, tagged under the target's key.
//! `cargo run --example fuzz_seeds` after a protocol change (docs/fuzzing.md).
use snaked::protocol::{
    AcquireReply, Announce, Command, Feedback, Key, LookupFilter, MAX_DATAGRAM, Message, Name,
    Route, Settings, encode,
};

fn main() -> std::io::Result<()> {
    let key = Key::from_bytes([0x5a; 32]);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/seeds/codec");
    std::fs::create_dir_all(&dir)?;
    let name = |s: &str| Name::new(s).expect("short");
    let messages = [
        ("lookup-all", Message::Lookup(LookupFilter::All)),
        (
            "lookup-family",
            Message::Lookup(LookupFilter::Family(name("SEA"))),
        ),
        (
            "lookup-names",
            Message::Lookup(LookupFilter::Names(vec![name("module-01"), name("m2")])),
        ),
        (
            "lookup-macs",
            Message::Lookup(LookupFilter::Macs(vec![[2, 0x53, 0x4e, 0, 0, 1]])),
        ),
        (
            "announce",
            Message::Announce(Announce {
                mac: [2, 0x53, 0x4e, 0, 0, 1],
                family: name("SEA"),
                name: name("module-01"),
                firmware: 0x100,
                owned: true,
            }),
        ),
        ("acquire", Message::Acquire([7; 16])),
        (
            "acquire-reply",
            Message::AcquireReply(AcquireReply {
                granted: true,
                module_nonce: [9; 16],
            }),
        ),
        ("release", Message::Release),
        ("settings", Message::Settings(Settings::default())),
        ("settings-ack", Message::SettingsAck(Settings::default())),
        ("command", Message::Command(Command::position(0.25))),
        (
            "feedback",
            Message::Feedback(Feedback {
                module_time_us: 1_000,
                last_command_seq: 3,
                position_rad: 0.1,
                ..Feedback::default()
            }),
        ),
    ];
    let mut buf = [0u8; MAX_DATAGRAM];
    for (seq, (file, msg)) in messages.iter().enumerate() {
        let route = Route {
            session: 0x5eed,
            seq: seq as u64 + 1,
            unit: 0,
        };
        let n = encode(route, msg, &key, &mut buf).expect("encodable");
        std::fs::write(dir.join(file), &buf[..n])?;
    }
    // A gateway's bundle: three units' commands in one datagram.
    let mut len = 0;
    for unit in 0..3 {
        let route = Route {
            session: 0x5eed,
            seq: 20,
            unit,
        };
        let msg = Message::Command(Command::position(0.1));
        len += encode(route, &msg, &key, &mut buf[len..]).expect("fits");
    }
    std::fs::write(dir.join("bundle"), &buf[..len])?;
    // A v1 Command (16-byte header, CRC-32 trailer): refused as version 1.
    let mut v1 = b"SN\x01\x08\x01\0\0\0\x05\0\0\0\x0c\0\0\0".to_vec();
    v1.extend_from_slice(&[0, 0, 0x80, 0x3f, 0, 0, 0xc0, 0x7f, 0, 0, 0x20, 0xc0]);
    v1.extend_from_slice(&[0x7e, 0x66, 0x7d, 0x5b]);
    std::fs::write(dir.join("v1-command"), v1)?;
    println!("seeds written to {}", dir.display());
    Ok(())
}
