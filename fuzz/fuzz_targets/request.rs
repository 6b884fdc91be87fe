//! The control socket's request parser, one line as the connection hands it over
//! (`api::parse_request`), then `controller.set`'s params and the build of the
//! controller they name (no loop needed). Properties: nothing panics; every refusal
//! is a well-formed JSON-RPC error line; the id is echoed exactly as sent; no request
//! with a key twice in some object is accepted.
#![no_main]
use libfuzzer_sys::fuzz_target;
use serde::Deserialize;
use serde_json::Value;
use serde_json::value::RawValue;
use snaked::controller_interface::{BuildContext, ConfigError, registry};
use snaked::controllers::REGISTRY;
use snaked::gait::{BodyLayout, GaitTable, Plane};
use snaked::module::MODULE_LENGTH_M;
use snaked::socket::api::{RequestId, RpcError, code, error_line, parse_request, result_line};
use snaked::socket::controller_set_params;

fuzz_target!(|line: &[u8]| {
    let expected = expected_id(line);
    let (id, error) = match parse_request(line) {
        Err(bad) => {
            let json = std::str::from_utf8(line)
                .is_ok_and(|t| serde_json::from_str::<serde::de::IgnoredAny>(t).is_ok());
            assert_eq!(
                bad.error.code == code::PARSE_ERROR,
                !json,
                "{:?}",
                bad.error
            );
            (bad.id, Some(bad.error))
        }
        Ok(req) => {
            let text = std::str::from_utf8(line).expect("accepted as UTF-8");
            let raw: &RawValue = serde_json::from_str(text).expect("accepted as JSON");
            assert!(!has_duplicate_key(raw, 0), "accepted with a key twice");
            assert_eq!(
                result_line(&req.id, &Value::Null),
                format!("{{\"id\":{},\"result\":null}}\n", req.id.get())
            );
            let error = match req.method.as_str() {
                "controller.set" => controller_set(req.params).err(),
                _ => None,
            };
            (req.id, error)
        }
    };
    if let Some(expected) = expected {
        let echoed: Value = serde_json::from_str(id.get()).expect("the id is JSON");
        assert_eq!(echoed, expected, "id {} not echoed", id.get());
    }
    if id.get() != "null" {
        let text = std::str::from_utf8(line).expect("an id was read from UTF-8");
        assert!(
            text.contains(id.get()),
            "id {} is not in the line",
            id.get()
        );
    }
    if let Some(error) = error {
        check_error_line(&id, &error);
    }
});

/// The id an independent reader finds: a number or a string member `id` of an object.
fn expected_id(line: &[u8]) -> Option<Value> {
    match serde_json::from_slice::<Value>(line).ok()? {
        Value::Object(mut top) => top
            .remove("id")
            .filter(|id| id.is_number() || id.is_string()),
        _ => None,
    }
}

/// Whether some object in `raw` has a key twice, found by walking raw values (nothing
/// converted). `false` also where it cannot tell: a key that is no valid string, or
/// deeper than 64 levels.
fn has_duplicate_key(raw: &RawValue, depth: usize) -> bool {
    struct Entries<'a>(Vec<(String, &'a RawValue)>);
    impl<'de: 'a, 'a> Deserialize<'de> for Entries<'a> {
        fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
            struct V;
            impl<'de> serde::de::Visitor<'de> for V {
                type Value = Entries<'de>;
                fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                    f.write_str("an object")
                }
                fn visit_map<A: serde::de::MapAccess<'de>>(
                    self,
                    mut map: A,
                ) -> Result<Entries<'de>, A::Error> {
                    let mut out = Vec::new();
                    while let Some(entry) = map.next_entry()? {
                        out.push(entry);
                    }
                    Ok(Entries(out))
                }
            }
            d.deserialize_map(V)
        }
    }
    if depth > 64 {
        return false;
    }
    let text = raw.get();
    let values: Vec<&RawValue> = match text.as_bytes().first() {
        Some(b'{') => {
            let Ok(Entries(entries)) = serde_json::from_str(text) else {
                return false;
            };
            let mut keys: Vec<&str> = entries.iter().map(|(k, _)| k.as_str()).collect();
            keys.sort_unstable();
            if keys.windows(2).any(|w| w[0] == w[1]) {
                return true;
            }
            entries.iter().map(|(_, v)| *v).collect()
        }
        Some(b'[') => serde_json::from_str(text).unwrap_or_default(),
        _ => return false,
    };
    values.into_iter().any(|v| has_duplicate_key(v, depth + 1))
}

/// `controller.set` as the socket serves it, short of installing the controller.
fn controller_set(params: snaked::socket::api::Params) -> Result<(), RpcError> {
    let (gait, sel) = controller_set_params(params)?;
    let layout = BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M);
    let table = GaitTable::default();
    let ctx = BuildContext {
        gait,
        layout: &layout,
        params: table.get(gait),
    };
    let e = match registry::build(REGISTRY, &sel, &ctx) {
        Ok(_) => return Ok(()),
        Err(e) => e,
    };
    // A configuration error names the field.
    if let ConfigError::Field { path: f, .. }
    | ConfigError::OutOfRange { field: f, .. }
    | ConfigError::Invalid { field: f, .. } = &e
    {
        assert!(!f.is_empty(), "{e}");
    }
    Err(RpcError::invalid_params(format!("{}: {e}", gait.name())))
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ErrorAnswer<'a> {
    #[serde(borrow)]
    id: &'a RawValue,
    error: ErrorObject,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ErrorObject {
    code: i64,
    message: String,
}

/// One line, `{"id": <as sent, or null>, "error": {"code": <known>, "message": ..}}`.
fn check_error_line(id: &RequestId, error: &RpcError) {
    let line = error_line(id, error);
    let body = line.strip_suffix('\n').expect("ends with a newline");
    assert!(!body.contains('\n'), "{line}");
    let prefix = format!("{{\"id\":{},\"error\":", id.get());
    assert!(body.starts_with(&prefix), "{line}");
    let answer: ErrorAnswer = serde_json::from_str(body).expect("an error answer is JSON");
    let id = answer.id.get();
    // A number as sent, a string that is one (a lone surrogate is not), or null.
    let echoable = id == "null"
        || id.starts_with(['-', '0', '1', '2', '3', '4', '5', '6', '7', '8', '9'])
        || serde_json::from_str::<String>(id).is_ok();
    assert!(echoable, "id {id} echoed: {line}");
    let known = [
        code::PARSE_ERROR,
        code::INVALID_REQUEST,
        code::METHOD_NOT_FOUND,
        code::INVALID_PARAMS,
    ];
    assert!(known.contains(&answer.error.code), "{line}");
    assert!(!answer.error.message.is_empty(), "{line}");
}
