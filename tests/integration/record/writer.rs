//! The recorder's MCAP file: channels, schemas and per-channel counts of a scripted run
//! read back with the `mcap` crate; ring overflow; the caps; clear errors at start;
//! Drop finishes the file.

use crate::support::record_fixture as fixture;

use fixture::*;
use foxglove::schemas::{FrameTransforms, SceneUpdate};
use snaked::live::LiveOptions;
use snaked::record::{
    CapReason, FileState, McapOptions, RecordError, RecordOptions, RecordState, RecordSummary,
    start,
};

fn record(items: &[snaked::record::RecordItem], opts: RecordOptions, world: bool) -> RecordSummary {
    let (catalog, _) = catalog();
    let (tx, rec) = start(opts, info(catalog, world)).expect("start");
    push_all(&tx, items);
    rec.finish().expect("finish")
}

#[test]
fn a_scripted_run_has_every_channel_with_its_schema_and_count() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("run.mcap");
    let (catalog, id) = catalog();
    let items = run(300, id, true);
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ..options(items.len())
    };
    let (tx, rec) = start(opts, info(catalog, true)).expect("start");
    push_all(&tx, &items);
    let summary = rec.finish().expect("finish");

    let file = read_mcap(&path);
    let expected = expected_counts_300();
    assert_eq!(file.counts, expected);
    assert_eq!(summary.per_topic, expected);
    let total: u64 = expected.values().sum();
    assert_eq!(summary.messages_written, total);
    assert_eq!(file.summary_messages, total);
    assert_eq!(summary.items, items.len() as u64);
    assert_eq!((summary.dropped, summary.capped), (0, None));
    assert_eq!(summary.bytes, std::fs::metadata(&path).expect("size").len());

    for (topic, (schema, schema_enc, msg_enc)) in &file.channels {
        match topic.as_str() {
            "/tf" => assert_eq!(schema, "foxglove.FrameTransforms"),
            "/scene/world" | "/scene/body" => assert_eq!(schema, "foxglove.SceneUpdate"),
            _ => {
                assert_eq!(
                    (schema_enc.as_str(), msg_enc.as_str()),
                    ("jsonschema", "json")
                );
                assert!(schema.starts_with("snaked."), "{topic}: {schema}");
            }
        }
        if msg_enc == "protobuf" {
            assert_eq!(schema_enc, "protobuf", "{topic}");
        }
    }

    // Signals are named from the catalog; the info carries the units.
    let signals = &file.first["/controller/signals"];
    let v: serde_json::Value = serde_json::from_slice(signals).expect("JSON");
    assert_eq!(v["engaged"], false);
    let info: serde_json::Value =
        serde_json::from_slice(&file.first["/controller/info"]).expect("JSON");
    assert_eq!(info["controller"], "fake_compliant");
    assert_eq!(info["report"]["signals"][0]["unit"], "rad");
    let windows: serde_json::Value =
        serde_json::from_slice(&file.first["/controller/windows"]).expect("JSON");
    assert_eq!(
        windows["fields"][0]["windows"].as_array().map(Vec::len),
        Some(2)
    );
    let joints: serde_json::Value = serde_json::from_slice(&file.first["/joints"]).expect("JSON");
    assert_eq!(
        joints["position_rad"].as_array().map(Vec::len),
        Some(MODULES)
    );
    let navigation: serde_json::Value =
        serde_json::from_slice(&file.first["/navigation"]).expect("JSON");
    assert_eq!(navigation["navigator"]["active"], false, "{navigation}");
    assert_eq!(
        navigation["navigator"]["travel_rad"],
        serde_json::Value::Null
    );
    assert_eq!(navigation["progress"]["stuck"], false, "{navigation}");
    let navigation: serde_json::Value =
        serde_json::from_slice(&file.last["/navigation"]).expect("JSON");
    assert_eq!(navigation["navigator"]["active"], true, "{navigation}");
    assert_eq!(
        navigation["navigator"]["choice"], "sidewind",
        "{navigation}"
    );
    assert_eq!(navigation["navigator"]["why"], "start", "{navigation}");
    let commands: serde_json::Value =
        serde_json::from_slice(&file.first["/commands"]).expect("JSON");
    assert_eq!(commands["velocity_rad_s"][0], serde_json::Value::Null);

    // The 3-D channels decode as Foxglove's well-known protobuf messages.
    use prost::Message as _;
    let tf = FrameTransforms::decode(&file.first["/tf"][..]).expect("FrameTransforms");
    let frames: Vec<_> = tf
        .transforms
        .iter()
        .map(|t| t.child_frame_id.as_str())
        .collect();
    assert_eq!(frames.len(), 1 + MODULES + 1, "world → body and every link");
    assert_eq!((frames[0], frames[1]), ("body", "link_0"));
    assert!(tf.transforms.iter().all(|t| t.parent_frame_id == "world"));
    let world = SceneUpdate::decode(&file.first["/scene/world"][..]).expect("SceneUpdate");
    assert_eq!(world.entities[0].frame_id, "world");
    assert_eq!(world.entities[0].cylinders.len(), 1, "the peg");
    let body = SceneUpdate::decode(&file.first["/scene/body"][..]).expect("SceneUpdate");
    assert_eq!(body.entities[0].frame_id, "body");
    assert_eq!(
        body.entities[0].cylinders.len(),
        MODULES + 1,
        "head and modules"
    );

    // Metadata: what the recording is of, the caller's pairs, the final status.
    let rec = &file.metadata["snaked.recording"];
    assert_eq!(rec["source"], "snake-lab");
    assert_eq!(rec["modules"], MODULES.to_string());
    assert!(rec["module_names"].contains("m5"));
    assert!(rec["layout"].contains("module_length_m"));
    assert!(rec.contains_key("world"));
    assert_eq!(file.metadata["snaked.metadata"]["scenario"], "test");
    let status = &file.metadata["snaked.status"];
    assert_eq!(status["messages_written"], total.to_string());
    assert_eq!(
        (status["dropped"].as_str(), status["capped"].as_str()),
        ("0", "none")
    );
}

#[test]
fn signals_plot_by_name_while_engaged() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("signals.mcap");
    let (catalog, id) = catalog();
    let items: Vec<_> = (0..120).map(|k| cycle(k, id, false)).collect();
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ..options(items.len())
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    push_all(&tx, &items);
    rec.finish().expect("finish");
    let bytes = std::fs::read(&path).expect("read");
    let mut engaged = 0;
    for m in mcap::MessageStream::new(&bytes).expect("stream") {
        let m = m.expect("message");
        if m.channel.topic != "/controller/signals" {
            continue;
        }
        let v: serde_json::Value = serde_json::from_slice(&m.data).expect("JSON");
        if v["engaged"] == true {
            engaged += 1;
            assert_eq!(v["signals"]["amplitude_mean_rad"], 0.4);
            assert_eq!(v["controller"], "fake_compliant");
        } else {
            assert_eq!(v["signals"], serde_json::json!({}));
        }
    }
    assert_eq!(engaged, 20);
    // No ground truth and no world: the body and its frame only.
    let file = read_mcap(&path);
    assert_eq!(file.counts.get("/scene/world"), None);
    assert_eq!(file.counts["/tf"], 6, "0, 20, ..., 100 ms");
}

#[test]
fn a_full_ring_drops_counts_and_the_file_says_so() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("overflow.mcap");
    let (catalog, id) = catalog();
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ring_capacity: 4,
        ..RecordOptions::default()
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    // Push faster than the writer drains until some are dropped (bounded).
    let (mut accepted, mut refused) = (0u64, 0u64);
    let mut k = 0;
    while refused < 10 && k < 1_000_000 {
        if tx.push(&cycle(k, id, false)) {
            accepted += 1;
        } else {
            refused += 1;
        }
        k += 1;
    }
    assert!(refused >= 10, "the ring never filled in {k} pushes");
    assert_eq!(tx.dropped(), refused);
    let summary = rec.finish().expect("finish");
    assert_eq!(summary.dropped, refused);
    assert_eq!(summary.items, accepted);
    let file = read_mcap(&path);
    assert_eq!(file.counts["/joints"], accepted);
    assert_eq!(
        file.metadata["snaked.status"]["dropped"],
        refused.to_string()
    );
    // After finish the ring refuses without counting.
    assert!(!tx.push(&cycle(0, id, false)));
    assert_eq!(tx.dropped(), refused);
}

#[test]
fn a_size_cap_finishes_a_valid_file_and_keeps_draining() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("capped.mcap");
    let (catalog, id) = catalog();
    // The smallest cap the recorder takes (chunks of 1/8 of it).
    let cap = snaked::record::MIN_MAX_BYTES;
    let opts = RecordOptions {
        mcap: Some(McapOptions {
            max_bytes: Some(cap),
            ..McapOptions::new(&path)
        }),
        ring_capacity: 256,
        ..RecordOptions::default()
    };
    let (tx, rec) = start(opts, info(catalog, true)).expect("start");
    // Cycles of the scripted run (made as they are pushed) until the cap is reached,
    // then as many again: drained, not written.
    let (mut k, mut pushed) = (0, 0u64);
    let mut push = |k: u64| {
        let items = events_at(k, id).into_iter().chain(stats_at(k));
        for item in items.chain([cycle(k, id, true)]) {
            assert!(tx.push_wait(&item), "refused");
            pushed += 1;
        }
    };
    while rec.status().capped.is_none() {
        assert!(k < 200_000, "the cap was never reached");
        push(k);
        k += 1;
    }
    for more in k..2 * k {
        push(more);
    }
    let summary = rec.finish().expect("finish");
    assert_eq!(summary.capped, Some(CapReason::MaxBytes));
    assert_eq!(summary.items, pushed, "drained to the end");
    assert_eq!(summary.dropped, 0, "push_wait waits instead");
    let file = read_mcap(&path);
    let joints = file.counts["/joints"];
    assert!(
        joints > 0 && joints <= k,
        "{joints} /joints messages of {}",
        2 * k
    );
    assert_eq!(summary.per_topic, file.counts);
    let size = std::fs::metadata(&path).expect("size").len();
    assert!(size >= cap, "stopped at {size} bytes, before the cap");
    // Past the cap by at most a chunk (1/8 of it) and the summary.
    assert!(
        size < cap + cap / 8 + 64 * 1024,
        "{size} bytes: far over the cap"
    );
    assert_eq!(file.metadata["snaked.status"]["capped"], "max_bytes");
}

#[test]
fn a_duration_cap_stops_at_the_recorded_loop_time() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("duration.mcap");
    let (catalog, id) = catalog();
    let items: Vec<_> = (0..500).map(|k| cycle(k, id, false)).collect();
    let opts = RecordOptions {
        mcap: Some(McapOptions {
            max_duration_s: Some(0.1),
            ..McapOptions::new(&path)
        }),
        ..options(items.len())
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    push_all(&tx, &items);
    let status_before = rec.status();
    let summary = rec.finish().expect("finish");
    assert_eq!(summary.capped, Some(CapReason::MaxDuration));
    assert_eq!(summary.items, 500);
    let file = read_mcap(&path);
    // Cycles at 0..=100 ms are written; the one at 100 ms reaches the cap.
    assert_eq!(file.counts["/joints"], 101);
    assert!(status_before.items <= 500);
}

#[test]
fn status_reports_progress_and_the_cap() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("status.mcap");
    let (catalog, id) = catalog();
    let opts = RecordOptions {
        mcap: Some(McapOptions {
            max_duration_s: Some(0.01),
            ..McapOptions::new(&path)
        }),
        ..options(100)
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    let s = rec.status();
    assert_eq!(s.state, RecordState::Recording);
    assert_eq!(s.path.as_deref(), Some(path.as_path()));
    let items: Vec<_> = (0..100).map(|k| cycle(k, id, false)).collect();
    push_all(&tx, &items);
    // Wait (bounded) for the writer to drain: it polls, nothing wakes it.
    for _ in 0..10_000 {
        if rec.status().items == 100 {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    let s = rec.status();
    assert_eq!(s.items, 100);
    assert_eq!(s.capped, Some(CapReason::MaxDuration));
    // Closed at the cap with its summary: finished, and all of it complete.
    assert_eq!(s.file, Some(FileState::Finished));
    assert_eq!(s.state, RecordState::Capped);
    // Not written, but not lost to a failure either.
    assert_eq!((s.error, s.lost), (None, 0));
    // What the control socket shows.
    let shown = serde_json::to_value(rec.probe().status()).expect("JSON");
    assert_eq!(shown["state"], "capped");
    assert_eq!(shown["capped"], "max_duration");
    assert_eq!(s.complete_s, 0.010);
    // Joints, commands, IMU, body estimate, navigation, signals a cycle over 0..=10 ms,
    // and the 3-D pair at 0 ms.
    assert_eq!(s.messages_written, 11 * 6 + 2);
    assert!(s.bytes > 0, "the finished file has its size");
    assert_eq!((s.dropped, s.live_clients), (0, 0));
    rec.finish().expect("finish");
}

#[test]
fn dropping_the_recorder_finishes_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("dropped.mcap");
    let (catalog, id) = catalog();
    let items: Vec<_> = (0..50).map(|k| cycle(k, id, false)).collect();
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ..options(items.len())
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    push_all(&tx, &items);
    drop(rec);
    let file = read_mcap(&path);
    assert_eq!(file.counts["/joints"], 50);
    assert!(file.metadata.contains_key("snaked.status"));
}

#[test]
fn a_missing_directory_is_a_clear_error_and_is_not_created() {
    let dir = tempfile::tempdir().expect("tempdir");
    let missing = dir.path().join("no-such-dir");
    let path = missing.join("run.mcap");
    let (catalog, _) = catalog();
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ..RecordOptions::default()
    };
    let err = start(opts, info(catalog, false)).err().expect("an error");
    assert!(
        matches!(err, RecordError::MissingDirectory { .. }),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(msg.contains(&*path.to_string_lossy()), "{msg}");
    assert!(msg.contains("does not exist"), "{msg}");
    assert!(!missing.exists());
}

#[test]
fn an_existing_file_is_not_overwritten() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("old.mcap");
    std::fs::write(&path, b"an earlier run").expect("write");
    let (catalog, _) = catalog();
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ..RecordOptions::default()
    };
    let err = start(opts, info(catalog, false)).err().expect("an error");
    let msg = err.to_string();
    assert!(matches!(err, RecordError::Create { .. }), "{err:?}");
    assert!(
        msg.contains(&*path.to_string_lossy()) && msg.contains("exists"),
        "{msg}"
    );
    assert_eq!(std::fs::read(&path).expect("read"), b"an earlier run");
}

#[test]
fn a_path_the_os_refuses_names_the_os_reason() {
    // A directory given as the file: the OS refuses, and the error says why.
    let dir = tempfile::tempdir().expect("tempdir");
    let (catalog, _) = catalog();
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(dir.path())),
        ..RecordOptions::default()
    };
    let err = start(opts, info(catalog, false)).err().expect("an error");
    let RecordError::Create { reason, .. } = &err else {
        panic!("{err:?}");
    };
    assert!(err.to_string().ends_with(&reason.to_string()), "{err}");
}

#[test]
fn bad_options_are_refused() {
    for opts in [
        RecordOptions {
            ring_capacity: 0,
            ..RecordOptions::default()
        },
        RecordOptions {
            scene_rate_hz: 0.0,
            ..RecordOptions::default()
        },
        RecordOptions {
            mcap: Some(McapOptions {
                max_duration_s: Some(f64::NAN),
                ..McapOptions::new("x.mcap")
            }),
            ..RecordOptions::default()
        },
        RecordOptions {
            mcap: Some(McapOptions {
                chunk_duration_s: 0.0,
                ..McapOptions::new("x.mcap")
            }),
            ..RecordOptions::default()
        },
    ] {
        let (catalog, _) = catalog();
        let err = start(opts, info(catalog, false)).err().expect("an error");
        assert!(matches!(err, RecordError::InvalidOption(_)), "{err:?}");
    }
}

#[test]
fn a_port_in_use_is_a_clear_error() {
    let taken = std::net::TcpListener::bind("127.0.0.1:0").expect("bind");
    let addr = taken.local_addr().expect("addr");
    let (catalog, _) = catalog();
    let opts = RecordOptions {
        live: Some(LiveOptions {
            addr,
            station: None,
            ..LiveOptions::default()
        }),
        ..RecordOptions::default()
    };
    let err = start(opts, info(catalog, false)).err().expect("an error");
    assert!(matches!(err, RecordError::Live { .. }), "{err:?}");
    assert!(err.to_string().contains(&addr.to_string()), "{err}");
}

#[test]
fn without_a_file_or_clients_nothing_is_written() {
    let (_, id) = catalog();
    let items: Vec<_> = (0..20).map(|k| cycle(k, id, false)).collect();
    let s = record(&items, options(items.len()), false);
    assert_eq!((s.items, s.messages_written, s.path), (20, 0, None));
}

#[test]
fn push_wait_loses_nothing_through_a_tiny_ring_and_stops_after_finish() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("wait.mcap");
    let (catalog, id) = catalog();
    let items: Vec<_> = (0..500).map(|k| cycle(k, id, false)).collect();
    let opts = RecordOptions {
        mcap: Some(McapOptions::new(&path)),
        ring_capacity: 2,
        ..RecordOptions::default()
    };
    let (tx, rec) = start(opts, info(catalog, false)).expect("start");
    push_all_waiting(&tx, &items);
    let summary = rec.finish().expect("finish");
    assert_eq!((summary.items, summary.dropped), (500, 0));
    assert_eq!(read_mcap(&path).counts["/joints"], 500);
    assert!(!tx.push_wait(&items[0]), "returns at once after finish");
}
