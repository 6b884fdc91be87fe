//! JSON Schemas of the JSON channels (`jsonschema` encoding in MCAP and the live view),
//! so Foxglove can complete message paths and other readers know the fields.

use serde_json::{Value, json};

fn numbers(unit: &str) -> Value {
    json!({"type": "array", "items": {"type": ["number", "null"]}, "description": unit})
}

fn header() -> Value {
    json!({
        "cycle": {"type": "integer", "description": "loop cycle index"},
        "t_ns": {"type": "integer", "description": "loop time, ns since the loop started"}
    })
}

fn object(title: &str, mut properties: Value, extra: Value) -> Value {
    if let (Some(p), Some(e)) = (properties.as_object_mut(), extra.as_object()) {
        p.extend(e.clone());
    }
    json!({"$schema": "https://json-schema.org/draft/2020-12/schema", "title": title,
           "type": "object", "properties": properties})
}

pub fn joints() -> Value {
    object(
        "snaked.Joints",
        header(),
        json!({
            "position_rad": numbers("rad, per module, head first"),
            "velocity_rad_s": numbers("rad/s"),
            "torque_nm": numbers("N·m"),
        }),
    )
}

pub fn commands() -> Value {
    object(
        "snaked.Commands",
        header(),
        json!({
            "position_rad": numbers("rad; null: not commanded"),
            "velocity_rad_s": numbers("rad/s; null: not commanded"),
        }),
    )
}

pub fn imu() -> Value {
    let xyz = |unit: &str| {
        json!({"type": "object", "description": unit,
               "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}})
    };
    object(
        "snaked.Imu",
        header(),
        json!({"modules": {"type": "array", "items": {"type": "object", "properties": {
            "accel_m_s2": xyz("specific force, m/s², module frame"),
            "gyro_rad_s": xyz("angular velocity, rad/s, module frame"),
        }}}}),
    )
}

pub fn body_estimate() -> Value {
    object(
        "snaked.BodyEstimate",
        header(),
        json!({
            "valid": {"type": "boolean", "description": "false until the estimator has settled, or on non-finite input"},
            "position_m": numbers("the virtual chassis' origin relative to the head link, world axes, m"),
            "orientation_wxyz": numbers("the virtual chassis' orientation in the estimate's world (z up, yaw 0 at the start)"),
            "heading_rad": {"type": "number", "description": "the chassis' forward (head-ward) axis in the ground plane, rad"},
            "round": {"type": "boolean", "description": "no clear main axis (coiled): the axis kept from before"},
            "odometry_m": numbers("the chassis origin's ground-plane position from contact odometry (the links on the ground taken to stay put), estimate's world, m"),
            "odometry_lifted": {"type": "boolean", "description": "part of the body was lifted, so odometry_m stood on contacts (false: the whole body down, it assumes no drift)"},
            "head_wxyz": numbers("the head link's orientation on the same world axes (with position_m and orientation_wxyz: the head in the chassis frame)"),
            "world": {"type": "object", "description": "the chassis in the external source's world (estimation::world_position)", "properties": {
                "state": {"type": "string", "enum": ["none", "aligning", "tracking", "stale"]},
                "position_m": numbers("the chassis' ground-plane position, the source's world, m"),
                "velocity_m_s": numbers("its velocity, m/s"),
                "heading_rad": {"type": "number", "description": "the chassis' heading in the source's world, rad"},
                "sd_m": {"type": "number", "description": "the position's standard deviation, m"},
                "age_s": {"type": ["number", "null"], "description": "loop time since the last accepted fix was measured, s"},
                "accepted": {"type": "integer"}, "rejected": {"type": "integer", "description": "fixes outside the gate"},
                "late": {"type": "integer", "description": "fixes older than what the estimate remembers"},
                "alignments": {"type": "integer", "description": "times the worlds were aligned"},
                "yaw_offset_rad": {"type": "number", "description": "the source's world's yaw against the estimate's, rad"}}},
            "fix": {"type": "object", "description": "the newest external fix (pose.external, ROS 2's pose topic)", "properties": {
                "number": {"type": "integer", "description": "0: none yet"},
                "position_m": numbers("in the source's world, m"),
                "orientation_wxyz": {"type": ["array", "null"], "items": {"type": "number"}, "description": "null: position only"},
                "age_s": {"type": ["number", "null"], "description": "loop time since it was measured, s; null: none"}}},
        }),
    )
}

pub fn navigation() -> Value {
    object(
        "snaked.Navigation",
        header(),
        json!({"progress": {"type": "object", "properties": {
            "stuck": {"type": "boolean", "description": "the joint torques have repeated each gait cycle: jammed (docs/navigation.md)"},
            "reason": {"type": "string", "enum": ["measuring", "changing", "torques_repeat"]},
            "repeat_error": {"type": ["number", "null"], "description": "the last whole cycle's RMS(τ(t) − τ(t − T)) / RMS(τ); null until measured"},
            "measuring_s": {"type": "number", "description": "seconds since the measurement restarted (a request that changes the gait, a blend, hold or limp restarts it)"},
        }},
        "navigator": {"type": "object", "properties": {
            "active": {"type": "boolean", "description": "navigating now (`navigate`)"},
            "travel_rad": {"type": ["number", "null"], "description": "the direction of travel, the pose estimate's world, rad"},
            "choice": {"type": ["string", "null"], "enum": ["sidewind", "back_off", "slither", "turn", null], "description": "what it runs"},
            "why": {"type": ["string", "null"], "enum": ["start", "stuck", "backed_off", "slither_time_up", "turned", "off_course", "steer", "no_progress", "off_line", null]},
            "switches": {"type": "integer", "description": "changes of gait or controller since it started"},
            "stopped": {"type": ["string", "null"], "enum": ["off", "operator", "estimate_invalid", "not_running", "refused", "arrived", null], "description": "why it stopped (docs/navigation.md)"},
            "goal_m": {"type": ["array", "null"], "items": {"type": "number"}, "description": "the goal [x, y], the position source's world, m; null: a direction only"},
            "by_position": {"type": "boolean", "description": "steering by position now (a goal and a valid position); false: by heading only"},
            "distance_m": {"type": ["number", "null"], "description": "to the goal, m (null while not by position)"},
            "cross_track_m": {"type": ["number", "null"], "description": "left of the line from where it started to the goal, m (null while not by position)"},
        }}}),
    )
}

pub fn controller_signals() -> Value {
    object(
        "snaked.ControllerSignals",
        header(),
        json!({
            "mode": {"type": "string"},
            "reason": {"type": "string"},
            "gait": {"type": "string"},
            "controller_id": {"type": "integer", "description": "0: none"},
            "controller": {"type": ["string", "null"]},
            "preset": {"type": ["string", "null"]},
            "engaged": {"type": "boolean"},
            "signals": {"type": "object", "additionalProperties": {"type": ["number", "null"]},
                        "description": "name → value while engaged; units in /controller/info"},
        }),
    )
}

pub fn controller_windows() -> Value {
    let window = json!({"type": "object",
        "properties": {"a": {"type": ["number", "null"]}, "b": {"type": ["number", "null"]}},
        "additionalProperties": {"type": ["number", "null"]},
        "description": "edges a, b in normalised arc length (null: open side) and the field's columns"});
    object(
        "snaked.ControllerWindows",
        header(),
        json!({
            "controller_id": {"type": "integer"},
            "fields": {"type": "array", "items": {"type": "object", "properties": {
                "name": {"type": "string"},
                "centralization": {"type": "string"},
                "enabled": {"type": "boolean"},
                "count": {"type": "integer"},
                "windows": {"type": "array", "items": window},
            }}},
        }),
    )
}

pub fn controller_info() -> Value {
    object(
        "snaked.ControllerInfo",
        json!({}),
        json!({
            "id": {"type": "integer"},
            "gait": {"type": "string"},
            "controller": {"type": "string"},
            "preset": {"type": "string"},
            "config": {"type": "object"},
            "report": {"type": "object", "description": "signals and fields with their units"},
        }),
    )
}

pub fn events() -> Value {
    object(
        "snaked.Event",
        json!({"t_ns": {"type": "integer"}}),
        json!({
            "kind": {"enum": ["mode", "request", "engaged", "released", "setpoint_fault"]},
            "mode": {"type": "string"},
            "reason": {"type": "string"},
            "ticket": {"type": "integer"},
            "request": {"type": "string"},
            "args": {"type": "object"},
            "applied": {"type": "boolean"},
            "error": {"type": ["string", "null"]},
            "continuity": {"enum": ["blended", "followed", "reconfigured", "handed_back", "installed"],
                           "description": "a change of a gait's parameters or controller: what became of its controller (docs/control-socket.md)"},
            "why": {"type": "string", "description": "why the controller was handed back or a new one installed"},
            "gait": {"type": "string"},
            "controller_id": {"type": "integer"},
            "controller": {"type": ["string", "null"]},
            "joint": {"type": "integer"},
        }),
    )
}

pub fn stats() -> Value {
    let summary = json!({"type": "object", "description": "µs", "properties": {
        "count": {"type": "integer"}, "mean_us": {"type": "number"}, "min_us": {"type": "number"},
        "p50_us": {"type": "number"}, "p99_us": {"type": "number"}, "p999_us": {"type": "number"},
        "max_us": {"type": "number"}}});
    object(
        "snaked.Stats",
        json!({"t_ns": {"type": "integer"}}),
        json!({
            "cycles": {"type": "integer"},
            "wakeup_latency": summary,
            "period_error": summary,
            "compute": summary,
            "bus_io": summary,
            "feedback_age": summary,
            "overruns": {"type": "integer"},
            "skipped_periods": {"type": "integer"},
            "late_feedback": {"type": "integer"},
            "bus_errors": {"type": "integer"},
            "recorder": {"type": "object", "properties": {
                "dropped": {"type": "integer", "description": "items the ring could not take, since the start"},
                "live_clients": {"type": "integer"}}},
        }),
    )
}
