//! What a controller reports each cycle, in fixed-size storage the loop fills without
//! allocating: a flat array of signal values and up to [`MAX_FIELDS`] window fields
//! (a windowed shape parameter: its windows' edges and a few columns per window). The
//! names and units of both live in a [`ReportSpec`], built with the controller off the
//! loop and kept by the control side ([`super::catalog`]).

use serde::Serialize;

/// Signal values a controller may report.
pub const MAX_SIGNALS: usize = 40;
/// Window fields a controller may report (e.g. amplitude, spatial frequency, phase).
pub const MAX_FIELDS: usize = 4;
/// Windows kept per field (a per-joint field of a 64-module body has 32).
pub const MAX_WINDOWS: usize = 32;
/// Columns per window (e.g. value, force, mode, absition).
pub const MAX_COLUMNS: usize = 6;

/// One windowed field: `count` windows on the body, the first [`MAX_WINDOWS`] kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowField {
    /// Windows on the body (may exceed [`MAX_WINDOWS`]; only that many are kept).
    pub count: usize,
    /// Edges in normalised arc length (infinite: that side is open).
    pub a: [f64; MAX_WINDOWS],
    pub b: [f64; MAX_WINDOWS],
    /// Per-window values, named by the field's [`FieldSpec::columns`].
    pub columns: [[f64; MAX_WINDOWS]; MAX_COLUMNS],
}

impl WindowField {
    pub const EMPTY: WindowField = WindowField {
        count: 0,
        a: [0.0; MAX_WINDOWS],
        b: [0.0; MAX_WINDOWS],
        columns: [[0.0; MAX_WINDOWS]; MAX_COLUMNS],
    };

    /// Windows kept (`count` capped at the capacity).
    pub fn len(&self) -> usize {
        self.count.min(MAX_WINDOWS)
    }

    pub fn is_empty(&self) -> bool {
        self.count == 0
    }
}

/// A controller's report after a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ControllerReport {
    /// Signal values in [`ReportSpec::signals`] order; unused entries are NaN.
    pub signals: [f64; MAX_SIGNALS],
    /// Window fields in [`ReportSpec::fields`] order.
    pub fields: [WindowField; MAX_FIELDS],
}

impl ControllerReport {
    pub const EMPTY: ControllerReport = ControllerReport {
        signals: [f64::NAN; MAX_SIGNALS],
        fields: [WindowField::EMPTY; MAX_FIELDS],
    };

    pub fn clear(&mut self) {
        *self = Self::EMPTY;
    }
}

impl Default for ControllerReport {
    fn default() -> Self {
        Self::EMPTY
    }
}

/// A signal's name and unit (`""` when dimensionless, `"count"` for counts).
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct SignalSpec {
    pub name: String,
    pub unit: String,
}

impl SignalSpec {
    pub fn new(name: impl Into<String>, unit: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            unit: unit.into(),
        }
    }
}

/// A window field's name, unit of its value, centralisation and column names.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct FieldSpec {
    pub name: String,
    /// `central`, `windowed` or `per_joint`.
    pub centralization: String,
    /// Whether the field complies (off: it stays at its nominal value).
    pub enabled: bool,
    /// At most [`MAX_COLUMNS`].
    pub columns: Vec<SignalSpec>,
}

/// Names and units of a controller's report, built off the loop.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize)]
pub struct ReportSpec {
    /// At most [`MAX_SIGNALS`].
    pub signals: Vec<SignalSpec>,
    /// At most [`MAX_FIELDS`].
    pub fields: Vec<FieldSpec>,
}

impl ReportSpec {
    /// Whether it fits the fixed-size report.
    pub fn fits(&self) -> bool {
        self.signals.len() <= MAX_SIGNALS
            && self.fields.len() <= MAX_FIELDS
            && self.fields.iter().all(|f| f.columns.len() <= MAX_COLUMNS)
    }
}
