use super::*;

fn err(line: &str) -> BadRequest {
    parse_request(line.as_bytes()).expect_err("should be refused")
}

#[test]
fn parses_a_request_with_params() {
    let r = parse_request(br#"{"id":7,"method":"gait.set","params":{"gait":"rolling"}}"#).unwrap();
    assert_eq!(r.id.get(), "7");
    assert_eq!(r.method, "gait.set");
    let mut p = r.params;
    assert_eq!(p.take_gait("gait").unwrap(), Some(GaitKind::Rolling));
    p.finish(&["gait"]).unwrap();
}

#[test]
fn classifies_bad_lines() {
    assert_eq!(err("{not json").error.code, code::PARSE_ERROR);
    assert_eq!(err("[1,2]").error.code, code::INVALID_REQUEST);
    assert_eq!(
        err(r#"{"method":"status"}"#).error.code,
        code::INVALID_REQUEST
    );
    let e = err(r#"{"id":"a"}"#);
    assert_eq!((e.error.code, e.id.get()), (code::INVALID_REQUEST, "\"a\""));
    assert_eq!(
        err(r#"{"id":1,"method":3}"#).error.code,
        code::INVALID_REQUEST
    );
    assert_eq!(
        err(r#"{"id":[1],"method":"x"}"#).error.code,
        code::INVALID_REQUEST
    );
    assert_eq!(
        err(r#"{"id":1,"method":"x","params":[]}"#).error.code,
        code::INVALID_PARAMS
    );
    assert_eq!(
        err(r#"{"id":1,"method":"x","extra":0}"#).error.code,
        code::INVALID_REQUEST
    );
}

#[test]
fn non_finite_numbers_name_their_field() {
    let r = parse_request(br#"{"id":1,"method":"m","params":{"taper":1e999}}"#).unwrap();
    let mut p = r.params;
    let e = p.take_f64("taper").unwrap_err();
    assert_eq!(e.code, code::INVALID_PARAMS);
    assert!(
        e.message.contains("taper") && e.message.contains("finite"),
        "{}",
        e.message
    );
}

#[test]
fn wrong_types_and_unknown_fields_are_named() {
    let r = parse_request(br#"{"id":1,"method":"m","params":{"rate_hz":"x","zz":1}}"#).unwrap();
    let mut p = r.params;
    let e = p.take_f64("rate_hz").unwrap_err();
    assert!(e.message.contains("rate_hz") && e.message.contains("string"));
    let e = p.finish(&["rate_hz"]).unwrap_err();
    assert!(e.message.contains("zz"), "{}", e.message);
}

#[test]
fn patch_fields_round_trip() {
    let r = parse_request(br#"{"id":1,"method":"m","params":{"taper":0.5,"helix_pitch_m":0.1}}"#)
        .unwrap();
    let mut p = r.params;
    let patch = p.take_patch().unwrap();
    assert_eq!(patch.taper, Some(0.5));
    assert_eq!(patch.helix_pitch_m, Some(0.1));
    assert_eq!(patch.amplitude_lat_rad, None);
    assert!(p.is_empty());
    let mut probe = ParamPatch::default();
    for f in PATCH_FIELDS {
        assert!(patch_slot(&mut probe, f).is_some(), "{f}");
    }
}

#[test]
fn ids_are_echoed_exactly_as_sent() {
    for id in [
        "123456789012345678901234567890",
        "-0",
        "1e3",
        "0.1000000000000000055511151231257827",
        "\"ü\\u0041\"",
    ] {
        let line = format!(r#"{{"id":{id},"method":"ping"}}"#);
        let r = parse_request(line.as_bytes()).unwrap();
        let answer = result_line(&r.id, &Value::Bool(true));
        assert_eq!(answer, format!("{{\"id\":{id},\"result\":true}}\n"));
    }
}

#[test]
fn duplicate_keys_are_refused_naming_the_key() {
    let e = err(r#"{"id":4,"method":"gait.set","params":{"gait":"rolling","gait":"slithering"}}"#);
    assert_eq!(e.error.code, code::INVALID_REQUEST);
    assert_eq!(e.id.get(), "4", "answered with the id");
    assert!(
        e.error.message.contains("duplicate key `gait`"),
        "{}",
        e.error.message
    );
    let e = err(r#"{"id":1,"id":2,"method":"ping"}"#);
    assert!(e.error.message.contains("duplicate key `id`"));
    let e = err(r#"{"id":1,"method":"x","params":{"config":{"a":{"b":1,"b":2}}}}"#);
    assert!(
        e.error.message.contains("duplicate key `b`"),
        "{}",
        e.error.message
    );
}

/// Found by `fuzz/fuzz_targets/request.rs`: a request refused for a duplicate key
/// was answered with its last id even when that id was a lone surrogate, which the
/// answer cannot carry (`{"id":"\ud800",...}` is not readable JSON text).
#[test]
fn a_duplicate_key_answer_echoes_only_an_echoable_id() {
    for (line, id) in [
        (r#"{"id":1,"id":"\ud800","method":"ping"}"#, "null"),
        (r#"{"id":1,"id":[2],"method":"ping"}"#, "null"),
        (
            r#"{"id":"\u00fc","method":"a","method":"b"}"#,
            r#""\u00fc""#,
        ),
    ] {
        let e = err(line);
        assert_eq!(
            (e.error.code, e.id.get()),
            (code::INVALID_REQUEST, id),
            "{line}"
        );
        assert!(
            e.error.message.contains("duplicate key"),
            "{line}: {:?}",
            e.error
        );
        let answer: Value = serde_json::from_str(&error_line(&e.id, &e.error)).unwrap();
        assert_eq!(answer["id"], serde_json::from_str::<Value>(id).unwrap());
    }
}

/// Found while writing `fuzz/fuzz_targets/request.rs`: the duplicate-key check gave
/// up at the first value serde could not convert (`1e999`, a lone surrogate, nesting
/// past serde's recursion limit), so a key twice after such a value went through
/// when that value was never read (the id, `jsonrpc`, a duplicate's first value).
#[test]
fn no_value_stops_the_duplicate_key_check() {
    let deep = format!("{}{}", "[".repeat(200), "]".repeat(200));
    for (line, key, id) in [
        (r#"{"id":1e999,"method":"ping","method":"ping"}"#.to_owned(), "method", "1e999"),
        (
            r#"{"jsonrpc":"\ud800","id":1,"method":"gait.set","params":{"gait":"rolling","gait":"slithering"}}"#.to_owned(),
            "gait",
            "1",
        ),
        (
            format!(r#"{{"jsonrpc":{deep},"id":2,"method":"ping","method":"ping"}}"#),
            "method",
            "2",
        ),
        (r#"{"id":"\ud800","method":"a","method":"b"}"#.to_owned(), "method", "null"),
        (
            r#"{"id":3,"method":"x","params":{"config":{"a":1e999,"a":2}}}"#.to_owned(),
            "a",
            "3",
        ),
        (r#"{"id":4,"method":"m","params":{"a":1,"\u0061":2}}"#.to_owned(), "a", "4"),
    ] {
        let e = err(&line);
        assert_eq!((e.error.code, e.id.get()), (code::INVALID_REQUEST, id), "{line}");
        assert_eq!(e.error.message, format!("duplicate key `{key}`"), "{line}");
    }
    // The same key in different objects, and keys' look-alikes inside strings, are not
    // duplicates.
    let line = r#"{"id":1,"method":"m","params":{"s":"a\",\"s\":","t":{"s":1},"u":[{"a":1},{"a":2}],"v":{}}}"#;
    let r = parse_request(line.as_bytes()).unwrap();
    assert_eq!(r.method, "m");
}

#[test]
fn a_lone_surrogate_and_deep_bad_numbers_say_what_and_where() {
    let e = err(r#"{"id":1,"method":"\ud800"}"#);
    assert!(
        e.error.message.contains("not a valid string"),
        "{}",
        e.error.message
    );
    let r =
        parse_request(br#"{"id":1,"method":"m","params":{"config":{"a":{"b":1e999}}}}"#).unwrap();
    let mut p = r.params;
    let e = p.take_json("config").unwrap_err();
    assert!(e.message.starts_with("`config.a.b`"), "{}", e.message);
}

#[test]
fn answer_lines_end_with_a_newline() {
    let l = error_line(&null_id(), &OperatorError::new(code::BUSY, "busy"));
    assert_eq!(
        l,
        "{\"id\":null,\"error\":{\"code\":-32000,\"message\":\"busy\"}}\n"
    );
}
