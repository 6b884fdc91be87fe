//! An independent reader: Python's `mcap` package (not the Rust crate that wrote the
//! file) reads a recording and reports its channels, schemas, counts and metadata.
//! Without the package this test skips, unless `CI` is set (`.ci/run` installs it).

use crate::support::record_fixture as fixture;

use std::process::Command;

use fixture::*;
use snaked::record::{McapOptions, RecordOptions, start};

const READER: &str = r#"
import json, sys
from mcap.reader import make_reader

with open(sys.argv[1], "rb") as f:
    reader = make_reader(f)
    summary = reader.get_summary()
    channels = {c.topic: [summary.schemas[c.schema_id].name,
                          summary.schemas[c.schema_id].encoding,
                          c.message_encoding]
                for c in summary.channels.values()}
    counts, joints = {}, None
    for schema, channel, message in reader.iter_messages():
        counts[channel.topic] = counts.get(channel.topic, 0) + 1
        if channel.topic == "/joints" and joints is None:
            joints = json.loads(message.data)
    metadata = {m.name: m.metadata for m in reader.iter_metadata()}
    print(json.dumps({
        "channels": channels,
        "counts": counts,
        "summary_count": summary.statistics.message_count,
        "metadata": metadata,
        "joints_modules": len(joints["position_rad"]),
    }))
"#;

fn python_has_mcap() -> bool {
    Command::new("python3")
        .args(["-c", "import mcap.reader"])
        .output()
        .is_ok_and(|o| o.status.success())
}

#[test]
fn pythons_mcap_reads_the_channels_and_counts() {
    if !python_has_mcap() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but python3 cannot import mcap (.ci/run should pip install mcap)"
        );
        println!("skipped: pip install mcap (python3 cannot import mcap)");
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("python.mcap");
    let (catalog, id) = catalog();
    let items = run(300, id, true);
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ..options(items.len())
    };
    let (tx, rec) = start(opts, info(catalog, true)).expect("start");
    push_all(&tx, &items);
    rec.finish().expect("finish");

    let out = Command::new("python3")
        .args(["-c", READER])
        .arg(&path)
        .output()
        .expect("run python3");
    assert!(
        out.status.success(),
        "python's mcap reader failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("the reader's JSON");

    let expected = expected_counts_300();
    let counts: std::collections::BTreeMap<String, u64> =
        serde_json::from_value(v["counts"].clone()).expect("counts");
    assert_eq!(counts, expected);
    assert_eq!(v["summary_count"], expected.values().sum::<u64>());
    let channels = v["channels"].as_object().expect("channels");
    assert_eq!(channels.len(), expected.len());
    assert_eq!(channels["/tf"][0], "foxglove.FrameTransforms");
    assert_eq!(channels["/tf"][1], "protobuf");
    assert_eq!(channels["/scene/world"][0], "foxglove.SceneUpdate");
    assert_eq!(channels["/joints"][0], "snaked.Joints");
    assert_eq!(channels["/joints"][1], "jsonschema");
    assert_eq!(channels["/joints"][2], "json");
    assert_eq!(v["joints_modules"], MODULES);
    assert_eq!(v["metadata"]["snaked.recording"]["source"], "snake-lab");
    assert_eq!(v["metadata"]["snaked.status"]["dropped"], "0");
}
