//! Typed controller configurations: the errors they give (naming the field and the
//! reason), presets with partial overrides merged onto them, and range checks.
//! Everything here runs off the loop.

use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::Value;

use super::interface::NominalMismatch;
use crate::num::Num;

/// Why a controller selection or configuration was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConfigError {
    #[error("unknown controller `{name}` for {gait} (known: {known})")]
    UnknownController {
        gait: &'static str,
        name: String,
        known: String,
    },
    #[error("controller {controller} has no preset `{name}` (known: {known})")]
    UnknownPreset {
        controller: &'static str,
        name: String,
        known: String,
    },
    #[error("controller {controller} does not run {gait} (it runs: {gaits})")]
    WrongGait {
        controller: &'static str,
        gait: &'static str,
        gaits: String,
    },
    /// The JSON does not match the configuration's type (unknown field, wrong type).
    #[error("`{path}`: {reason}")]
    Field { path: String, reason: String },
    #[error("`{field}` = {} is out of range [{}, {}]", Num(*value), Num(*min), Num(*max))]
    OutOfRange {
        field: String,
        value: f64,
        min: f64,
        max: f64,
    },
    #[error("`{field}`: {reason}")]
    Invalid { field: String, reason: String },
    #[error(transparent)]
    Nominal(#[from] NominalMismatch),
}

impl ConfigError {
    /// The same error with its field path under `prefix` (e.g. `config`).
    pub fn under(self, prefix: &str) -> Self {
        let join = |p: String| {
            if p.is_empty() || p == "." {
                prefix.to_owned()
            } else {
                format!("{prefix}.{p}")
            }
        };
        match self {
            Self::Field { path, reason } => Self::Field {
                path: join(path),
                reason,
            },
            Self::OutOfRange {
                field,
                value,
                min,
                max,
            } => Self::OutOfRange {
                field: join(field),
                value,
                min,
                max,
            },
            Self::Invalid { field, reason } => Self::Invalid {
                field: join(field),
                reason,
            },
            other => other,
        }
    }

    pub fn invalid(field: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Invalid {
            field: field.into(),
            reason: reason.into(),
        }
    }
}

/// `value` must be finite and within `[min, max]`.
/// The joint-torque filter every torque-driven controller has: its low-pass cutoff
/// (0.01 to 200 Hz) and its dead-band (up to the module's torque).
pub fn check_torque_filter(cutoff_hz: f64, deadband_nm: f64) -> Result<(), ConfigError> {
    check_range("torque_cutoff_hz", cutoff_hz, 0.01, 200.0)?;
    check_range(
        "torque_deadband_nm",
        deadband_nm,
        0.0,
        crate::module::MODULE_MAX_TORQUE_NM,
    )
}

pub fn check_range(field: &str, value: f64, min: f64, max: f64) -> Result<(), ConfigError> {
    if value.is_nan() || !(min..=max).contains(&value) {
        return Err(ConfigError::OutOfRange {
            field: field.to_owned(),
            value,
            min,
            max,
        });
    }
    Ok(())
}

/// Merges `patch` onto `base`: objects key by key (recursively), anything else
/// replaces. A partial override of a preset is merged this way.
pub fn merge(base: &mut Value, patch: &Value) {
    match (base, patch) {
        (Value::Object(b), Value::Object(p)) => {
            for (k, v) in p {
                match b.get_mut(k) {
                    Some(slot) => merge(slot, v),
                    None => {
                        b.insert(k.clone(), v.clone());
                    }
                }
            }
        }
        (b, p) => *b = p.clone(),
    }
}

/// `base` (a preset) with `overrides` merged onto it, read back as `C` (whose fields
/// deny unknown names): an error names the field's path and the reason.
pub fn with_overrides<C: Serialize + DeserializeOwned>(
    base: &C,
    overrides: Option<&Value>,
) -> Result<C, ConfigError> {
    let Some(overrides) = overrides else {
        return from_json(to_json(base));
    };
    if !overrides.is_object() {
        return Err(ConfigError::Field {
            path: String::new(),
            reason: "a configuration override must be an object".into(),
        });
    }
    let mut v = to_json(base);
    merge(&mut v, overrides);
    from_json(v)
}

/// A configuration as JSON (unbounded range ends come out as `null`).
pub fn to_json<C: Serialize>(c: &C) -> Value {
    serde_json::to_value(c).expect("configurations serialise (string keys only)")
}

/// JSON read as `C`, with the failing field's path.
pub fn from_json<C: DeserializeOwned>(v: Value) -> Result<C, ConfigError> {
    serde_path_to_error::deserialize(v).map_err(|e| ConfigError::Field {
        path: e.path().to_string(),
        reason: e.inner().to_string(),
    })
}

/// Serde for a range end that may be unbounded: `null` is −∞ (lower end) or +∞
/// (upper end), as the configuration is shown.
pub mod bound {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
        if v.is_finite() {
            s.serialize_f64(*v)
        } else {
            s.serialize_none()
        }
    }

    pub fn lower<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NEG_INFINITY))
    }

    pub fn upper<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
        Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;
    use serde_json::json;

    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Inner {
        k: f64,
        #[serde(serialize_with = "bound::serialize", deserialize_with = "bound::upper")]
        max: f64,
    }

    #[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Outer {
        a: Inner,
        b: bool,
    }

    fn base() -> Outer {
        Outer {
            a: Inner {
                k: 1.0,
                max: f64::INFINITY,
            },
            b: true,
        }
    }

    #[test]
    fn a_partial_override_changes_only_what_it_names() {
        let c = with_overrides(&base(), Some(&json!({"a": {"k": 2.0}}))).unwrap();
        assert_eq!(c.a.k, 2.0);
        assert!(c.b && c.a.max == f64::INFINITY, "null reads back unbounded");
        let c = with_overrides(&base(), Some(&json!({"a": {"max": 3.0}}))).unwrap();
        assert_eq!((c.a.k, c.a.max), (1.0, 3.0));
        assert_eq!(with_overrides(&base(), None).unwrap(), base());
    }

    #[test]
    fn errors_name_the_field() {
        let e = with_overrides(&base(), Some(&json!({"a": {"kk": 2.0}}))).unwrap_err();
        assert!(
            e.to_string().contains("a.kk") || e.to_string().contains("kk"),
            "{e}"
        );
        let e = with_overrides(&base(), Some(&json!({"a": {"k": "x"}}))).unwrap_err();
        assert!(e.to_string().starts_with("`a.k`"), "{e}");
        let e = e.under("config");
        assert!(e.to_string().starts_with("`config.a.k`"), "{e}");
        assert!(with_overrides(&base(), Some(&json!(3))).is_err());
        let e = check_range("x", f64::NAN, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("`x`"), "{e}");
        assert!(check_range("x", 1.0, 0.0, 1.0).is_ok());
    }
}
