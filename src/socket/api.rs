//! The wire format: parsing requests, typed access to their params, error codes.
//!
//! Requests are parsed in two steps so that errors can name the offending field:
//! the line is first checked as JSON with every value kept raw (which does not
//! convert numbers, so `1e999` gets through), then each param is converted on its
//! own and a failure says which field and why.
use std::collections::BTreeMap;

use serde::Serialize;
use serde_json::Value;
use serde_json::value::RawValue;

use crate::gait::{GaitKind, ParamPatch};
use crate::num::Num;

pub use crate::operator::error::{OperatorError, code};

/// A request's id exactly as the client wrote it (a JSON number or string), so the
/// answer echoes it byte for byte: `123456789012345678901234567890` and `-0` come back
/// as sent, not as a double.
pub type RequestId = Box<RawValue>;

/// The id of an answer to a request whose id could not be read.
pub fn null_id() -> RequestId {
    RawValue::from_string("null".to_owned()).expect("null is JSON")
}

/// One parsed request line.
#[derive(Debug)]
pub struct Request {
    /// Echoed in the answer: a JSON number or string, as sent.
    pub id: RequestId,
    pub method: String,
    pub params: Params,
}

/// A line that is not a valid request: the error and the id to answer with
/// (`null` when the id could not be read).
#[derive(Debug)]
pub struct BadRequest {
    pub id: RequestId,
    pub error: OperatorError,
}

type RawMap = BTreeMap<String, Box<RawValue>>;

/// Parse one request line (without its newline).
pub fn parse_request(line: &[u8]) -> Result<Request, BadRequest> {
    let bad = |id: &RawValue, code: i64, message: String| BadRequest {
        id: id.to_owned(),
        error: OperatorError::new(code, message),
    };
    let null = null_id();
    let null = null.as_ref();
    let text = std::str::from_utf8(line)
        .map_err(|e| bad(null, code::PARSE_ERROR, format!("invalid UTF-8: {e}")))?;
    // Syntax only: raw values are skipped, numbers are not converted.
    let raw: Box<RawValue> = serde_json::from_str(text)
        .map_err(|e| bad(null, code::PARSE_ERROR, format!("invalid JSON: {e}")))?;
    if !raw.get().starts_with('{') {
        let what = json_kind(raw.get());
        return Err(bad(
            null,
            code::INVALID_REQUEST,
            format!("a request must be a JSON object, got {what}"),
        ));
    }
    let mut top: RawMap = serde_json::from_str(raw.get())
        .map_err(|e| bad(null, code::INVALID_REQUEST, format!("invalid request: {e}")))?;
    // The id first, so that even a request refused for a duplicate key is answered
    // with its id (when the id itself can be echoed).
    if let Err(dup) = unique_keys(raw.get()) {
        let id = match top.get("id") {
            Some(raw_id) if echoable_id(raw_id).is_ok() => raw_id,
            _ => null,
        };
        return Err(bad(id, code::INVALID_REQUEST, dup));
    }

    let id = match top.remove("id") {
        None => return Err(bad(null, code::INVALID_REQUEST, "missing `id`".into())),
        Some(raw_id) => match echoable_id(&raw_id) {
            Ok(()) => raw_id,
            Err(msg) => return Err(bad(null, code::INVALID_REQUEST, msg)),
        },
    };
    let method = match top.remove("method") {
        None => return Err(bad(&id, code::INVALID_REQUEST, "missing `method`".into())),
        Some(m) => serde_json::from_str::<String>(m.get()).map_err(|e| {
            let what = json_kind(m.get());
            let msg = if what == "a string" {
                format!("`method` is not a valid string: {e}")
            } else {
                format!("`method` must be a string, got {what}")
            };
            bad(&id, code::INVALID_REQUEST, msg)
        })?,
    };
    let params = match top.remove("params") {
        None => RawMap::new(),
        Some(p) if p.get() == "null" => RawMap::new(),
        Some(p) if p.get().starts_with('{') => serde_json::from_str(p.get())
            .map_err(|e| bad(&id, code::INVALID_PARAMS, format!("`params`: {e}")))?,
        Some(p) => {
            let what = json_kind(p.get());
            let msg = format!("`params` must be an object, got {what}");
            return Err(bad(&id, code::INVALID_PARAMS, msg));
        }
    };
    // A "jsonrpc": "2.0" member is tolerated so JSON-RPC clients work unchanged.
    top.remove("jsonrpc");
    if let Some(extra) = top.keys().next() {
        let msg = format!("unknown member `{extra}` (a request has id, method, params)");
        return Err(bad(&id, code::INVALID_REQUEST, msg));
    }
    Ok(Request {
        id,
        method,
        params: Params { fields: params },
    })
}

/// Whether an answer can echo `raw_id`: a number, or a string that is valid (a lone
/// surrogate is not, and would make the answer unreadable).
fn echoable_id(raw_id: &RawValue) -> Result<(), String> {
    match json_kind(raw_id.get()) {
        "a number" => Ok(()),
        "a string" => serde_json::from_str::<String>(raw_id.get())
            .map(drop)
            .map_err(|e| format!("`id` is not a valid string: {e}")),
        what => Err(format!("`id` must be a number or a string, got {what}")),
    }
}

/// What kind of JSON value a raw text is, for error messages.
fn json_kind(raw: &str) -> &'static str {
    match raw.trim_start().as_bytes().first() {
        Some(b'{') => "an object",
        Some(b'[') => "an array",
        Some(b'"') => "a string",
        Some(b't' | b'f') => "a boolean",
        Some(b'n') => "null",
        Some(b'-' | b'0'..=b'9') => "a number",
        _ => "nothing",
    }
}

/// A request's params, taken out field by field; `finish` refuses leftovers.
#[derive(Debug, Default)]
pub struct Params {
    fields: RawMap,
}

impl Params {
    /// From a JSON value that must be an object (an operator's call from elsewhere).
    pub fn from_value(v: &Value) -> Result<Params, OperatorError> {
        if !v.is_object() {
            return Err(OperatorError::invalid_params("`params` must be an object"));
        }
        let fields: RawMap = serde_json::from_str(&v.to_string())
            .map_err(|e| OperatorError::invalid_params(format!("`params`: {e}")))?;
        Ok(Params { fields })
    }

    pub fn is_empty(&self) -> bool {
        self.fields.is_empty()
    }

    pub fn contains(&self, name: &str) -> bool {
        self.fields.contains_key(name)
    }

    /// A number param: absent → `None`; not a number, or not finite as an f64
    /// (e.g. `1e999`) → an error naming the field.
    pub fn take_f64(&mut self, name: &str) -> Result<Option<f64>, OperatorError> {
        let Some(raw) = self.fields.remove(name) else {
            return Ok(None);
        };
        let text = raw.get();
        if !matches!(text.as_bytes().first(), Some(b'-' | b'0'..=b'9')) {
            let what = json_kind(text);
            return Err(OperatorError::invalid_params(format!(
                "`{name}` must be a number, got {what}"
            )));
        }
        match serde_json::from_str::<f64>(text) {
            Ok(v) if v.is_finite() => Ok(Some(v)),
            _ => Err(OperatorError::invalid_params(format!(
                "`{name}` = {text} is not a finite number"
            ))),
        }
    }

    /// A number param that must lie in `min..=max`.
    pub fn take_f64_in(
        &mut self,
        name: &str,
        min: f64,
        max: f64,
    ) -> Result<Option<f64>, OperatorError> {
        match self.take_f64(name)? {
            Some(v) if !(min..=max).contains(&v) => Err(OperatorError::invalid_params(format!(
                "`{name}` = {} is out of range [{}, {}]",
                Num(v),
                Num(min),
                Num(max)
            ))),
            other => Ok(other),
        }
    }

    /// A string param: absent → `None`; another type → an error naming the field.
    pub fn take_str(&mut self, name: &str) -> Result<Option<String>, OperatorError> {
        let Some(raw) = self.fields.remove(name) else {
            return Ok(None);
        };
        serde_json::from_str::<String>(raw.get())
            .map(Some)
            .map_err(|_| {
                let what = json_kind(raw.get());
                OperatorError::invalid_params(format!("`{name}` must be a string, got {what}"))
            })
    }

    /// A param of any JSON type, parsed: absent → `None`; a number that is not a
    /// finite double (`1e999`) → an error naming the field.
    pub fn take_json(&mut self, name: &str) -> Result<Option<Value>, OperatorError> {
        let Some(raw) = self.fields.remove(name) else {
            return Ok(None);
        };
        // With the path to what failed inside it (e.g. `config.amplitude.gains.max`).
        let mut de = serde_json::Deserializer::from_str(raw.get());
        serde_path_to_error::deserialize::<_, Value>(&mut de)
            .map(Some)
            .map_err(|e| {
                let path = e.path().to_string();
                let at = if path.is_empty() || path == "." {
                    name.to_owned()
                } else {
                    format!("{name}.{path}")
                };
                OperatorError::invalid_params(format!("`{at}`: {}", e.inner()))
            })
    }

    /// A gait name param.
    pub fn take_gait(&mut self, name: &str) -> Result<Option<GaitKind>, OperatorError> {
        match self.take_str(name)? {
            None => Ok(None),
            Some(s) => GaitKind::from_name(&s).map(Some).ok_or_else(|| {
                let known: Vec<&str> = GaitKind::ALL.iter().map(|k| k.name()).collect();
                OperatorError::invalid_params(format!(
                    "`{name}`: unknown gait `{s}` (known: {})",
                    known.join(", ")
                ))
            }),
        }
    }

    /// Every `ParamPatch` field present, each a finite number.
    pub fn take_patch(&mut self) -> Result<ParamPatch, OperatorError> {
        let mut patch = ParamPatch::default();
        for name in PATCH_FIELDS {
            if let Some(v) = self.take_f64(name)? {
                *patch_slot(&mut patch, name).expect("PATCH_FIELDS names ParamPatch fields") =
                    Some(v);
            }
        }
        Ok(patch)
    }

    /// Refuse any field not taken yet; `expected` lists the method's fields.
    pub fn finish(self, expected: &[&str]) -> Result<(), OperatorError> {
        match self.fields.keys().next() {
            None => Ok(()),
            Some(extra) if expected.is_empty() => Err(OperatorError::invalid_params(format!(
                "unknown field `{extra}` (this method takes no params)"
            ))),
            Some(extra) => Err(OperatorError::invalid_params(format!(
                "unknown field `{extra}` (expected one of: {})",
                expected.join(", ")
            ))),
        }
    }
}

/// The fields of `ParamPatch`, as named on the wire.
pub const PATCH_FIELDS: [&str; 10] = [
    "amplitude_lat_rad",
    "amplitude_dor_rad",
    "offset_lat_rad",
    "offset_dor_rad",
    "spatial_freq_rad",
    "temporal_freq_rad_s",
    "phase_shift_rad",
    "taper",
    "helix_radius_m",
    "helix_pitch_m",
];

fn patch_slot<'a>(p: &'a mut ParamPatch, name: &str) -> Option<&'a mut Option<f64>> {
    Some(match name {
        "amplitude_lat_rad" => &mut p.amplitude_lat_rad,
        "amplitude_dor_rad" => &mut p.amplitude_dor_rad,
        "offset_lat_rad" => &mut p.offset_lat_rad,
        "offset_dor_rad" => &mut p.offset_dor_rad,
        "spatial_freq_rad" => &mut p.spatial_freq_rad,
        "temporal_freq_rad_s" => &mut p.temporal_freq_rad_s,
        "phase_shift_rad" => &mut p.phase_shift_rad,
        "taper" => &mut p.taper,
        "helix_radius_m" => &mut p.helix_radius_m,
        "helix_pitch_m" => &mut p.helix_pitch_m,
        _ => return None,
    })
}

/// Refuses a JSON text in which some object has a key twice (serde would keep the last
/// silently): the error names the key. `text` is valid JSON (checked before). One pass
/// over the text that converts no value, so nothing before a duplicate (`1e999`, a lone
/// surrogate, deep nesting) can end the check early.
fn unique_keys(text: &str) -> Result<(), String> {
    use std::collections::BTreeSet;
    let bytes = text.as_bytes();
    // The keys seen in each open object; `None` for an open array.
    let mut open: Vec<Option<BTreeSet<String>>> = Vec::new();
    let mut expect_key = false;
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'{' => {
                open.push(Some(BTreeSet::new()));
                expect_key = true;
            }
            b'[' => open.push(None),
            b'}' | b']' => {
                open.pop();
                expect_key = false;
            }
            b',' => expect_key = matches!(open.last(), Some(Some(_))),
            b'"' => {
                let end = string_end(bytes, i);
                if std::mem::take(&mut expect_key) {
                    let raw = &text[i..end];
                    // Keys compare as decoded ("a" and "\u0061" are one key).
                    let key = serde_json::from_str::<String>(raw)
                        .unwrap_or_else(|_| raw.get(1..raw.len() - 1).unwrap_or(raw).to_owned());
                    if let Some(Some(seen)) = open.last_mut()
                        && !seen.insert(key.clone())
                    {
                        return Err(format!("duplicate key `{key}`"));
                    }
                }
                i = end;
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    Ok(())
}

/// Just past the closing quote of the JSON string that opens at `start`.
fn string_end(bytes: &[u8], start: usize) -> usize {
    let mut i = start + 1;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    bytes.len()
}

/// The answer line for a result.
pub fn result_line(id: &RawValue, result: &Value) -> String {
    #[derive(Serialize)]
    struct Answer<'a> {
        id: &'a RawValue,
        result: &'a Value,
    }
    to_line(&Answer { id, result })
}

/// The answer line for an error.
pub fn error_line(id: &RawValue, error: &OperatorError) -> String {
    #[derive(Serialize)]
    struct Answer<'a> {
        id: &'a RawValue,
        error: &'a OperatorError,
    }
    to_line(&Answer { id, error })
}

/// A stream message line (no id): `{"method": .., "params": ..}`.
pub fn stream_line(method: &str, params: &Value) -> String {
    #[derive(Serialize)]
    struct Message<'a> {
        method: &'a str,
        params: &'a Value,
    }
    to_line(&Message { method, params })
}

fn to_line(v: &impl Serialize) -> String {
    // Serialising a `Value` or plain structs of them cannot fail (string keys only).
    let mut s = serde_json::to_string(v).expect("JSON values always serialise");
    s.push('\n');
    s
}

#[cfg(test)]
#[path = "api_tests.rs"]
mod tests;
