//! JSON bodies of the JSON channels, serialised straight from the records through
//! borrowing views (no intermediate `serde_json::Value`). Non-finite numbers become
//! `null` (serde_json's rule): an uncommanded set-point, an open window edge, an unused
//! signal.

use serde::Serialize;
use serde::ser::{SerializeMap, SerializeSeq, Serializer};

use super::cycle::{CycleRecord, JointSample, RecordEvent};
use crate::controller_interface::catalog::ControllerInfo;
use crate::controller_interface::report::{MAX_COLUMNS, MAX_FIELDS, MAX_SIGNALS, WindowField};
use crate::rt::messages::LoopRequest;
use crate::rt::stats::LoopStats;

/// One f32 per joint, picked by `pick`.
struct Column<'a> {
    joints: &'a [JointSample],
    pick: fn(&JointSample) -> f32,
}

impl Serialize for Column<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(self.joints.iter().map(self.pick))
    }
}

fn column<'a>(rec: &'a CycleRecord, pick: fn(&JointSample) -> f32) -> Column<'a> {
    Column {
        joints: rec.joints(),
        pick,
    }
}

/// `/joints`: feedback.
#[derive(Serialize)]
pub struct Joints<'a> {
    cycle: u64,
    t_ns: u64,
    position_rad: Column<'a>,
    velocity_rad_s: Column<'a>,
    torque_nm: Column<'a>,
}

impl<'a> Joints<'a> {
    pub fn new(rec: &'a CycleRecord) -> Self {
        Self {
            cycle: rec.cycle,
            t_ns: rec.t_ns,
            position_rad: column(rec, |j| j.position_rad),
            velocity_rad_s: column(rec, |j| j.velocity_rad_s),
            torque_nm: column(rec, |j| j.torque_nm),
        }
    }
}

/// `/commands`: set-points sent (null: not commanded).
#[derive(Serialize)]
pub struct Commands<'a> {
    cycle: u64,
    t_ns: u64,
    position_rad: Column<'a>,
    velocity_rad_s: Column<'a>,
}

impl<'a> Commands<'a> {
    pub fn new(rec: &'a CycleRecord) -> Self {
        Self {
            cycle: rec.cycle,
            t_ns: rec.t_ns,
            position_rad: column(rec, |j| j.cmd_position_rad),
            velocity_rad_s: column(rec, |j| j.cmd_velocity_rad_s),
        }
    }
}

#[derive(Serialize)]
struct Xyz {
    x: f32,
    y: f32,
    z: f32,
}

impl From<[f32; 3]> for Xyz {
    fn from([x, y, z]: [f32; 3]) -> Self {
        Self { x, y, z }
    }
}

struct ImuModules<'a>(&'a [JointSample]);

impl Serialize for ImuModules<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Module {
            accel_m_s2: Xyz,
            gyro_rad_s: Xyz,
        }
        s.collect_seq(self.0.iter().map(|j| Module {
            accel_m_s2: j.accel_m_s2.into(),
            gyro_rad_s: j.gyro_rad_s.into(),
        }))
    }
}

/// `/imu`: each module's accelerometer and gyro, in its own frame.
#[derive(Serialize)]
pub struct Imu<'a> {
    cycle: u64,
    t_ns: u64,
    modules: ImuModules<'a>,
}

impl<'a> Imu<'a> {
    pub fn new(rec: &'a CycleRecord) -> Self {
        Self {
            cycle: rec.cycle,
            t_ns: rec.t_ns,
            modules: ImuModules(rec.joints()),
        }
    }
}

/// `/body/estimate`: the estimators' body estimate of the cycle.
#[derive(Serialize)]
pub struct BodyEstimateMsg<'a> {
    cycle: u64,
    t_ns: u64,
    #[serde(flatten)]
    body: &'a crate::controller_interface::BodyEstimate,
}

impl<'a> BodyEstimateMsg<'a> {
    pub fn new(rec: &'a CycleRecord) -> Self {
        Self {
            cycle: rec.cycle,
            t_ns: rec.t_ns,
            body: &rec.body,
        }
    }
}

/// `/navigation`: whether the running gait makes way (the stuck detector) and what
/// the navigator does.
#[derive(Serialize)]
pub struct NavigationMsg<'a> {
    cycle: u64,
    t_ns: u64,
    progress: Progress<'a>,
    navigator: &'a crate::navigation::state::NavigatorState,
}

/// The report with a NaN repeat error as `null` (JSON has no NaN).
struct Progress<'a>(&'a crate::navigation::progress::ProgressReport);

impl Serialize for Progress<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let p = self.0;
        let mut st = s.serialize_struct("Progress", 4)?;
        st.serialize_field("stuck", &p.stuck)?;
        st.serialize_field("reason", &p.reason)?;
        st.serialize_field(
            "repeat_error",
            &p.repeat_error.is_finite().then_some(p.repeat_error),
        )?;
        st.serialize_field("measuring_s", &p.measuring_s)?;
        st.end()
    }
}

impl<'a> NavigationMsg<'a> {
    pub fn new(rec: &'a CycleRecord) -> Self {
        Self {
            cycle: rec.cycle,
            t_ns: rec.t_ns,
            progress: Progress(&rec.progress),
            navigator: &rec.navigator,
        }
    }
}

/// The report's signals as `{name: value}`, names from the catalog.
struct Signals<'a> {
    info: Option<&'a ControllerInfo>,
    values: &'a [f64; MAX_SIGNALS],
}

impl Serialize for Signals<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let specs = self.info.map_or(&[][..], |i| &i.report.signals[..]);
        let mut m = s.serialize_map(Some(specs.len().min(MAX_SIGNALS)))?;
        for (spec, v) in specs.iter().zip(self.values) {
            m.serialize_entry(&spec.name, v)?;
        }
        m.end()
    }
}

/// `/controller/signals`: who drives the joints and, while a controller is engaged,
/// its signals (`{}` otherwise: the report only means something while engaged).
#[derive(Serialize)]
pub struct ControllerSignals<'a> {
    cycle: u64,
    t_ns: u64,
    mode: crate::safety::failsafe::Mode,
    reason: crate::safety::failsafe::Reason,
    gait: crate::gait::GaitKind,
    controller_id: u64,
    controller: Option<&'static str>,
    preset: Option<&'static str>,
    engaged: bool,
    signals: Signals<'a>,
}

impl<'a> ControllerSignals<'a> {
    pub fn new(rec: &'a CycleRecord, info: Option<&'a ControllerInfo>) -> Self {
        let values = &rec.report.signals;
        Self {
            cycle: rec.cycle,
            t_ns: rec.t_ns,
            mode: rec.mode,
            reason: rec.reason,
            gait: rec.gait,
            controller_id: rec.controller_id,
            controller: info.map(|i| i.controller),
            preset: info.map(|i| i.preset),
            engaged: rec.engaged,
            signals: Signals {
                info: info.filter(|_| rec.engaged),
                values,
            },
        }
    }
}

/// One window: edges and the field's named columns.
struct Window<'a> {
    field: &'a WindowField,
    names: &'a [crate::controller_interface::report::SignalSpec],
    k: usize,
}

impl Serialize for Window<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let names = &self.names[..self.names.len().min(MAX_COLUMNS)];
        let mut m = s.serialize_map(Some(2 + names.len()))?;
        m.serialize_entry("a", &self.field.a[self.k])?;
        m.serialize_entry("b", &self.field.b[self.k])?;
        for (c, name) in names.iter().enumerate() {
            m.serialize_entry(&name.name, &self.field.columns[c][self.k])?;
        }
        m.end()
    }
}

struct Windows<'a> {
    field: &'a WindowField,
    names: &'a [crate::controller_interface::report::SignalSpec],
}

impl Serialize for Windows<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(self.field.len()))?;
        for k in 0..self.field.len() {
            seq.serialize_element(&Window {
                field: self.field,
                names: self.names,
                k,
            })?;
        }
        seq.end()
    }
}

#[derive(Serialize)]
struct Field<'a> {
    name: &'a str,
    centralization: &'a str,
    enabled: bool,
    /// Windows on the body (only the first `MAX_WINDOWS` are kept).
    count: usize,
    windows: Windows<'a>,
}

struct Fields<'a> {
    info: &'a ControllerInfo,
    fields: &'a [WindowField; MAX_FIELDS],
}

impl Serialize for Fields<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(
            self.info
                .report
                .fields
                .iter()
                .zip(self.fields)
                .map(|(spec, field)| Field {
                    name: &spec.name,
                    centralization: &spec.centralization,
                    enabled: spec.enabled,
                    count: field.count,
                    windows: Windows {
                        field,
                        names: &spec.columns,
                    },
                }),
        )
    }
}

/// `/controller/windows`: each window field's used windows (`a`, `b` in normalised arc
/// length, null = open side) and named columns.
#[derive(Serialize)]
pub struct ControllerWindows<'a> {
    cycle: u64,
    t_ns: u64,
    controller_id: u64,
    fields: Fields<'a>,
}

impl<'a> ControllerWindows<'a> {
    /// `None` unless a known controller with window fields is engaged.
    pub fn new(rec: &'a CycleRecord, info: Option<&'a ControllerInfo>) -> Option<Self> {
        let info = info.filter(|i| rec.engaged && !i.report.fields.is_empty())?;
        Some(Self {
            cycle: rec.cycle,
            t_ns: rec.t_ns,
            controller_id: rec.controller_id,
            fields: Fields {
                info,
                fields: &rec.report.fields,
            },
        })
    }
}

/// `/events`: one JSON object per event, `kind` says which.
#[derive(Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
enum EventBody<'a> {
    Mode {
        t_ns: u64,
        mode: crate::safety::failsafe::Mode,
        reason: crate::safety::failsafe::Reason,
    },
    Request {
        t_ns: u64,
        ticket: u64,
        #[serde(flatten)]
        request: &'a LoopRequest,
        applied: bool,
        /// What became of the gait's controller (a change of its parameters or
        /// controller).
        #[serde(flatten)]
        continuity: Option<crate::rt::messages::Continuity>,
        /// Why it was refused.
        error: Option<String>,
    },
    Engaged {
        t_ns: u64,
        gait: crate::gait::GaitKind,
        controller_id: u64,
        controller: Option<&'static str>,
    },
    Released {
        t_ns: u64,
        gait: crate::gait::GaitKind,
        controller_id: u64,
        controller: Option<&'static str>,
    },
    SetpointFault {
        t_ns: u64,
        joint: usize,
        controller_id: u64,
        controller: Option<&'static str>,
    },
}

/// Serialises an event; `name` names a controller id.
pub fn write_event(
    out: &mut Vec<u8>,
    t_ns: u64,
    event: &RecordEvent,
    name: impl Fn(u64) -> Option<&'static str>,
) -> serde_json::Result<()> {
    let body = match event {
        RecordEvent::Mode { mode, reason } => EventBody::Mode {
            t_ns,
            mode: *mode,
            reason: *reason,
        },
        RecordEvent::Request {
            ticket,
            request,
            result,
        } => EventBody::Request {
            t_ns,
            ticket: *ticket,
            request,
            applied: result.is_ok(),
            continuity: result.ok().flatten(),
            error: result.err().map(|e| e.to_string()),
        },
        RecordEvent::Engaged {
            gait,
            controller_id,
        } => EventBody::Engaged {
            t_ns,
            gait: *gait,
            controller_id: *controller_id,
            controller: name(*controller_id),
        },
        RecordEvent::Released {
            gait,
            controller_id,
        } => EventBody::Released {
            t_ns,
            gait: *gait,
            controller_id: *controller_id,
            controller: name(*controller_id),
        },
        RecordEvent::SetpointFault {
            joint,
            controller_id,
        } => EventBody::SetpointFault {
            t_ns,
            joint: *joint,
            controller_id: *controller_id,
            controller: name(*controller_id),
        },
    };
    serde_json::to_writer(out, &body)
}

/// `/stats`: the loop's statistics summary.
#[derive(Serialize)]
pub struct Stats {
    t_ns: u64,
    #[serde(flatten)]
    report: crate::rt::stats::StatsReport,
    recorder: RecorderHealth,
}

/// What the recorder itself lost and serves, with each `/stats` message: a viewer sees
/// drops as they happen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct RecorderHealth {
    /// Items the loop could not push because the ring was full, since the start.
    pub dropped: u64,
    /// Live-view clients connected now.
    pub live_clients: usize,
}

impl Stats {
    pub fn new(t_ns: u64, stats: &LoopStats, recorder: RecorderHealth) -> Self {
        Self {
            t_ns,
            report: stats.report(),
            recorder,
        }
    }
}

#[cfg(test)]
#[path = "encode_tests.rs"]
mod tests;
