//! Malformed and invalid requests: each gets the right error code, names what is
//! wrong, leaves the connection usable and never reaches the loop.
use crate::support::socket;

use serde_json::Value;
use snaked::socket::api::code;
use socket::{Harness, LoopSpec, error_code, error_message, raw};

/// Send `line`, expect error `code` with a message containing `needle`, then
/// check the connection still answers.
fn expect_error(h: &Harness, line: &str, want: i64, needle: &str) -> Value {
    let mut c = h.client();
    let a = raw(&mut c, line);
    assert_eq!(error_code(&a), want, "{line} → {a}");
    let msg = error_message(&a);
    assert!(
        msg.contains(needle),
        "{line}: message {msg:?} lacks {needle:?}"
    );
    let ok = raw(&mut c, r#"{"id":"after","method":"ping"}"#);
    assert_eq!(
        ok["result"]["pong"], true,
        "connection unusable after {line}"
    );
    a
}

#[test]
fn invalid_json_is_a_parse_error() {
    let h = Harness::default_server();
    let a = expect_error(
        &h,
        r#"{"id":1,"method":"status""#,
        code::PARSE_ERROR,
        "JSON",
    );
    assert_eq!(a["id"], Value::Null);
    expect_error(&h, "not json at all", code::PARSE_ERROR, "JSON");
    assert!(h.fake.seen().is_empty());
}

#[test]
fn non_objects_and_bad_envelopes_are_invalid_requests() {
    let h = Harness::default_server();
    expect_error(&h, "[1,2,3]", code::INVALID_REQUEST, "object");
    expect_error(&h, "42", code::INVALID_REQUEST, "object");
    let a = expect_error(&h, r#"{"id":5}"#, code::INVALID_REQUEST, "method");
    assert_eq!(a["id"], 5, "the id is echoed when it could be read");
    expect_error(&h, r#"{"method":"status"}"#, code::INVALID_REQUEST, "id");
    expect_error(
        &h,
        r#"{"id":true,"method":"status"}"#,
        code::INVALID_REQUEST,
        "id",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":7}"#,
        code::INVALID_REQUEST,
        "method",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"status","x":1}"#,
        code::INVALID_REQUEST,
        "x",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"status","params":[1]}"#,
        code::INVALID_PARAMS,
        "params",
    );
}

#[test]
fn unknown_method() {
    let h = Harness::default_server();
    let a = expect_error(
        &h,
        r#"{"id":"x","method":"fly"}"#,
        code::METHOD_NOT_FOUND,
        "fly",
    );
    assert_eq!(a["id"], "x");
}

#[test]
fn wrong_param_types_name_the_field() {
    let h = Harness::default_server();
    expect_error(
        &h,
        r#"{"id":1,"method":"gait.set","params":{"gait":3}}"#,
        code::INVALID_PARAMS,
        "gait",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"telemetry.subscribe","params":{"rate_hz":"fast"}}"#,
        code::INVALID_PARAMS,
        "rate_hz",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"gait":"slithering","taper":[0.1]}}"#,
        code::INVALID_PARAMS,
        "taper",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"gait.set","params":{"gait":"swimming"}}"#,
        code::INVALID_PARAMS,
        "swimming",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"gait.set"}"#,
        code::INVALID_PARAMS,
        "gait",
    );
    assert!(h.fake.seen().is_empty());
}

#[test]
fn unknown_fields_are_refused() {
    let h = Harness::default_server();
    expect_error(
        &h,
        r#"{"id":1,"method":"status","params":{"verbose":true}}"#,
        code::INVALID_PARAMS,
        "verbose",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"hold","params":{"now":1}}"#,
        code::INVALID_PARAMS,
        "now",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"gait":"rolling","amplitude":0.2}}"#,
        code::INVALID_PARAMS,
        "amplitude",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"blend_time_s":1,"gait":"rolling"}}"#,
        code::INVALID_PARAMS,
        "blend_time_s",
    );
    assert!(h.fake.seen().is_empty());
}

#[test]
fn out_of_range_values_are_refused() {
    let h = Harness::default_server();
    expect_error(
        &h,
        r#"{"id":1,"method":"telemetry.subscribe","params":{"rate_hz":500}}"#,
        code::INVALID_PARAMS,
        "rate_hz",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"telemetry.subscribe","params":{"rate_hz":0}}"#,
        code::INVALID_PARAMS,
        "rate_hz",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"blend_time_s":0.01}}"#,
        code::INVALID_PARAMS,
        "blend_time_s",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"blend_time_s":31}}"#,
        code::INVALID_PARAMS,
        "blend_time_s",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"gait":"slithering","taper":5}}"#,
        code::INVALID_PARAMS,
        "taper",
    );
    assert!(h.fake.seen().is_empty());
}

#[test]
fn non_finite_values_and_peak_speed_are_refused() {
    let h = Harness::default_server();
    // serde_json cannot represent 1e999 as an f64: still reported per field.
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"gait":"slithering","amplitude_lat_rad":1e999}}"#,
        code::INVALID_PARAMS,
        "amplitude_lat_rad",
    );
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"blend_time_s":-1e999}}"#,
        code::INVALID_PARAMS,
        "blend_time_s",
    );
    // Each value in range, but together the joints would move faster than 3.46 rad/s.
    expect_error(
        &h,
        r#"{"id":1,"method":"params.set","params":{"gait":"slithering","amplitude_lat_rad":1.2,"temporal_freq_rad_s":3.4}}"#,
        code::INVALID_PARAMS,
        "slithering",
    );
    assert!(h.fake.seen().is_empty(), "nothing invalid reaches the loop");
}

#[test]
fn oversize_lines_are_refused_and_the_connection_survives() {
    let h = Harness::new(LoopSpec::default(), |c| c.max_line_bytes = 1024);
    let mut c = h.client();
    let huge = format!(
        r#"{{"id":1,"method":"status","params":{{"pad":"{}"}}}}"#,
        "x".repeat(100_000)
    );
    let a = raw(&mut c, &huge);
    assert_eq!(error_code(&a), code::LINE_TOO_LONG, "{a}");
    let ok = raw(&mut c, r#"{"id":2,"method":"status"}"#);
    assert_eq!(ok["id"], 2);
    assert_eq!(ok["result"]["modules"], 8);
    // Just under the limit is fine (then refused for its unknown field, not its size).
    let pad = "y".repeat(900);
    let near = raw(
        &mut c,
        &format!(r#"{{"id":3,"method":"ping","params":{{"pad":"{pad}"}}}}"#),
    );
    assert_eq!(error_code(&near), code::INVALID_PARAMS);
    // Several oversize lines in a row, each reported once.
    c.send_line(&huge).unwrap();
    c.send_line(&huge).unwrap();
    c.send_line(r#"{"id":4,"method":"ping"}"#).unwrap();
    assert_eq!(error_code(&c.next_message().unwrap()), code::LINE_TOO_LONG);
    assert_eq!(error_code(&c.next_message().unwrap()), code::LINE_TOO_LONG);
    assert_eq!(c.next_message().unwrap()["id"], 4);
}

#[test]
fn blank_lines_are_ignored_and_jsonrpc_member_tolerated() {
    let h = Harness::default_server();
    let mut c = h.client();
    c.send_line("").unwrap();
    c.send_line("   ").unwrap();
    let a = raw(&mut c, r#"{"jsonrpc":"2.0","id":9,"method":"ping"}"#);
    assert_eq!(a["id"], 9);
    assert_eq!(a["result"]["pong"], true);
}
