//! Compliant slithering as SPEC §5 reads, written for clarity, not speed: every window
//! evaluated at every joint from its definition, every field kept apart, the phase grid
//! scanned whole. The controller's step is pinned to it over long runs.

use crate::controller_interface::TickClock;
use std::f64::consts::PI;

use super::*;
use crate::controller_interface::testing::{ObservationBuf, engage_at};
use crate::gait::Plane;

/// One field: its windows, their values and the last shape forces on them.
#[derive(Default)]
struct Field {
    windows: Vec<Window>,
    values: Vec<f64>,
    forces: Vec<f64>,
}

impl Field {
    fn at(&self, s: f64, m: f64) -> f64 {
        let w = self.windows.iter().map(|w| w.weight(s, m));
        self.values.iter().zip(w).map(|(v, w)| v * w).sum()
    }
}

struct Reference {
    config: CompliantSlitheringConfig,
    layout: BodyLayout,
    nominal: Nominal,
    /// (joint index, s) of the lateral joints.
    lateral: Vec<(usize, f64)>,
    m: f64,
    filter: TorqueFilter,
    tau: Vec<f64>,
    manager: WindowManager<[ParamState; 3]>,
    /// States and windows of the central and per-joint fields.
    fixed: [Vec<(Window, ParamState)>; 3],
    fields: [Field; 3],
    last_t: Option<f64>,
    t: f64,
    born: usize,
    dropped: usize,
}

impl Reference {
    fn new(layout: &BodyLayout, nominal: Nominal, config: CompliantSlitheringConfig) -> Self {
        let n = layout.len();
        let lateral: Vec<(usize, f64)> = (0..n)
            .filter(|&i| layout.planes[i] == Plane::Lateral)
            .map(|i| (i, layout.s[i]))
            .collect();
        // Per joint: from midway to the previous lateral joint to midway to the next.
        let mid = |k: usize| 0.5 * (lateral[k - 1].1 + lateral[k].1);
        let per_joint = (0..lateral.len()).map(|k| Window {
            a: if k == 0 { f64::NEG_INFINITY } else { mid(k) },
            b: if k + 1 == lateral.len() {
                f64::INFINITY
            } else {
                mid(k + 1)
            },
        });
        let fixed = Param::ALL.map(|p| match config.param(p).centralization {
            Centralization::Central => vec![(Window::EVERYWHERE, ParamState::default())],
            Centralization::PerJoint => {
                per_joint.clone().map(|w| (w, Default::default())).collect()
            }
            Centralization::Windowed => Vec::new(),
        });
        let m = steepness_for_width(config.edge_width_modules / (n as f64 + 1.0));
        let mut r = Self {
            config,
            layout: layout.clone(),
            nominal,
            lateral,
            m,
            filter: TorqueFilter::new(n, config.torque_cutoff_hz, config.torque_deadband_nm),
            tau: vec![0.0; n],
            manager: WindowManager::new(n + 9, MAX_WINDOWS),
            fixed,
            fields: Default::default(),
            last_t: None,
            t: nominal.t0_s,
            born: 0,
            dropped: 0,
        };
        let (ws, omega) = (nominal.params.spatial_freq_rad, nominal.phase_at(r.t));
        let nominal = Default::default();
        r.manager
            .update(|s| ws * s - omega, nominal, Slope::Unknown);
        r.place();
        r
    }

    fn windowed(&self, p: Param) -> bool {
        self.config.param(p).centralization == Centralization::Windowed
    }

    fn nominal(&self, p: Param) -> f64 {
        match p {
            Param::Amplitude => self.nominal.params.amplitude_lat_rad,
            Param::SpatialFreq => self.nominal.params.spatial_freq_rad,
            Param::Phase => self.nominal.phase_at(self.t),
        }
    }

    /// Every field's windows and values from the states.
    fn place(&mut self) {
        for p in Param::ALL {
            let (i, nominal) = (p.index(), self.nominal(p));
            let states: Vec<(Window, ParamState)> = if self.windowed(p) {
                let w = self.manager.windows();
                w.map(|t| (t.window, t.payload[i])).collect()
            } else {
                self.fixed[i].clone()
            };
            let f = &mut self.fields[i];
            f.windows = states.iter().map(|(w, _)| *w).collect();
            f.values = states.iter().map(|(_, s)| s.value(nominal)).collect();
        }
    }

    fn step(&mut self, t: f64, reported: &[f64], out: &mut [f64]) {
        let dt = self.last_t.map_or(0.0, |last| (t - last).max(0.0));
        (self.last_t, self.t) = (Some(t), t);
        self.filter.update(dt, reported, &mut self.tau);
        if Param::ALL.iter().any(|&p| self.windowed(p)) {
            let (fields, m) = (&self.fields, self.m);
            let phase = |s| phase(fields, m, s);
            let ev = self
                .manager
                .update(phase, Default::default(), Slope::Unknown);
            self.born += ev.born_at_head + ev.born_at_tail;
            self.dropped += ev.dropped_at_head + ev.dropped_at_tail;
        }
        self.place();
        self.forces();
        self.integrate(dt);
        self.place();
        out.fill(0.0);
        for &(i, s) in &self.lateral {
            out[i] = self.fields[0].at(s, self.m) * phase(&self.fields, self.m, s).sin();
        }
        self.nominal.add_offsets(&self.layout, out);
    }

    /// SPEC's window-local Jacobian: ∂h/∂A_j = w_j·sin φ, ∂h/∂ωS_j ≈ w_j·A·cos φ·∫w_j,
    /// ∂h/∂Ω_j = −A·cos φ·w_j; forces `Jᵀ·τ`.
    fn forces(&mut self) {
        let m = self.m;
        let mut forces = self.fields.each_ref().map(|f| vec![0.0; f.windows.len()]);
        for &(i, s) in &self.lateral {
            let tau = self.tau[i];
            if tau == 0.0 {
                continue;
            }
            let a = self.fields[0].at(s, m);
            let (sin, cos) = phase(&self.fields, m, s).sin_cos();
            let [fa, fs, fp] = &mut forces;
            let [wa, ws, wp] = self.fields.each_ref().map(|f| &f.windows);
            for (f, w) in fa.iter_mut().zip(wa) {
                *f += w.weight(s, m) * sin * tau;
            }
            for (f, w) in fs.iter_mut().zip(ws) {
                *f += w.weight(s, m) * a * cos * w.integral(s, m) * tau;
            }
            for (f, w) in fp.iter_mut().zip(wp) {
                *f -= a * cos * w.weight(s, m) * tau;
            }
        }
        for (field, f) in self.fields.iter_mut().zip(forces) {
            field.forces = f;
        }
    }

    fn integrate(&mut self, dt: f64) {
        for p in Param::ALL {
            let (pc, i, nominal) = (*self.config.param(p), p.index(), self.nominal(p));
            if !pc.enabled {
                continue;
            }
            let forces = &self.fields[i].forces;
            let sign = self.config.sign;
            if self.windowed(p) {
                for (w, &f) in self.manager.payloads_mut().zip(forces) {
                    w[i].step(&pc.gains, sign, f, nominal, dt);
                }
            } else {
                for ((_, st), &f) in self.fixed[i].iter_mut().zip(forces) {
                    st.step(&pc.gains, sign, f, nominal, dt);
                }
            }
        }
    }

    fn mean(&self, p: Param) -> f64 {
        let f = &self.fields[p.index()];
        let sum: f64 = self.lateral.iter().map(|&(_, s)| f.at(s, self.m)).sum();
        sum / self.lateral.len().max(1) as f64
    }
}

/// φ(s) = Σ ωS_j·∫₀^s w_j − Σ Ω_j·w_j(s).
fn phase(fields: &[Field; 3], m: f64, s: f64) -> f64 {
    let ws = &fields[Param::SpatialFreq.index()];
    let integrals = ws.windows.iter().map(|w| w.integral(s, m));
    let integral: f64 = ws.values.iter().zip(integrals).map(|(v, i)| v * i).sum();
    integral - fields[Param::Phase.index()].at(s, m)
}

fn close(what: &str, ours: f64, theirs: f64) {
    let tol = 1e-9 * theirs.abs().max(1.0);
    let same = ours == theirs || (ours - theirs).abs() <= tol;
    assert!(same, "{what}: {ours} vs {theirs}");
}

/// Runs the controller and the reference side by side for `steps` cycles under
/// `torque(k, i, set_point)` and compares set-points, fields and report every cycle.
fn compare(
    preset: &str,
    layout: &BodyLayout,
    params: &GaitParams,
    steps: usize,
    torque: impl Fn(usize, usize, f64) -> f64,
) {
    let n = layout.len();
    let config = CompliantSlitheringConfig::preset(preset).unwrap();
    let mut c = CompliantSlithering::new(layout, params, config);
    let t0 = 0.3;
    engage_at(&mut c, layout, params, t0);
    let engaged = |t: f64| Nominal::at_phase(params, params.temporal_freq_rad_s * t, t);
    let mut r = Reference::new(layout, engaged(t0), config);
    let (mut ours, mut theirs, mut tau) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let buf = ObservationBuf::new(n);
    let pos = vec![0.0; n];
    let mut report = ControllerReport::EMPTY;
    let (mut t, mut travelled) = (t0, (0, 0));
    let mut clock = TickClock::default();
    for k in 0..steps {
        // Now and then a late cycle (skipped periods); late on, engaged afresh.
        t += if k % 997 == 0 { 3e-3 } else { 1e-3 };
        if k == steps * 4 / 5 {
            engage_at(&mut c, layout, params, t);
            clock.restart();
            travelled = (travelled.0 + r.born, travelled.1 + r.dropped);
            r = Reference::new(layout, engaged(t), config);
        }
        c.step(clock.tick(t), &buf.observe(&pos, &tau), &mut ours);
        r.step(t, &tau, &mut theirs);
        let at = |what: &str| format!("{preset} n {n} step {k} {what}");
        for (i, (a, b)) in ours.iter().zip(&theirs).enumerate() {
            close(&at(&format!("joint {i}")), *a, *b);
        }
        for p in Param::ALL {
            let (windows, values, forces) = c.field(p);
            let f = &r.fields[p.index()];
            assert_eq!(windows.len(), f.windows.len(), "{}", at(p.name()));
            for (j, (w, v)) in f.windows.iter().zip(&f.values).enumerate() {
                let name = at(&format!("{} window {j}", p.name()));
                close(&name, windows[j].a, w.a);
                close(&name, windows[j].b, w.b);
                close(&name, values[j], *v);
                close(&name, forces[j], f.forces[j]);
            }
            close(&at("mean"), c.lateral_mean(p), r.mean(p));
        }
        c.report(&mut report);
        assert_eq!(report.signals[3], r.manager.len() as f64, "{}", at("count"));
        assert_eq!(report.signals[4], r.born as f64, "{}", at("born"));
        assert_eq!(report.signals[5], r.dropped as f64, "{}", at("dropped"));
        for (i, x) in tau.iter_mut().enumerate() {
            *x = torque(k, i, ours[i]);
        }
    }
    if Param::ALL.iter().any(|&p| r.windowed(p)) {
        let (born, dropped) = (travelled.0 + r.born, travelled.1 + r.dropped);
        assert!(
            born > 0 && dropped > 0,
            "{preset}: windows were born and dropped"
        );
    }
}

/// Steady torques (the bench's), pushes switched on and off joint by joint, and a
/// travelling sinusoid.
fn torques() -> [fn(usize, usize, f64) -> f64; 3] {
    [
        |_, i, _| ((i % 7) as f64 - 3.0) * 0.8,
        |k, i, x| {
            let on = (k / 500 + i) % 3 == 0;
            if on { -3.0 * x.signum() } else { 0.0 }
        },
        |k, i, _| 2.5 * (1.3e-3 * k as f64 - 0.7 * i as f64).sin(),
    ]
}

#[test]
fn every_preset_follows_the_reference_for_thousands_of_steps() {
    let params = GaitParams::default_for(crate::gait::GaitKind::Slithering);
    // Backwards, fewer waves, steered: windows are born at the tail.
    let other = GaitParams {
        amplitude_lat_rad: 0.6,
        spatial_freq_rad: 2.3 * PI,
        temporal_freq_rad_s: -1.4,
        offset_lat_rad: 0.1,
        ..params
    };
    let [steady, pushes, sinusoid] = torques();
    let cases = [
        (18, Plane::Lateral, steady, &params),
        (18, Plane::Lateral, pushes, &other),
        (18, Plane::Lateral, sinusoid, &params),
        (5, Plane::Lateral, pushes, &params),
        (19, Plane::Dorsal, sinusoid, &other),
        (2, Plane::Dorsal, steady, &params), // one lateral joint
        (1, Plane::Dorsal, steady, &params), // none
    ];
    for (preset, _) in CompliantSlitheringConfig::PRESETS {
        for (n, first, torque, params) in cases {
            let layout = BodyLayout::alternating(n, first, 0.064);
            compare(preset, &layout, params, 5000, torque);
        }
    }
}

#[test]
fn long_bodies_follow_the_reference() {
    let params = GaitParams::default_for(crate::gait::GaitKind::Slithering);
    let layout = BodyLayout::alternating(64, Plane::Lateral, 0.064);
    let [steady, pushes, sinusoid] = torques();
    for (preset, torque) in [
        ("a_ws_omega", steady),
        ("a_ws_omega", pushes),
        ("a_ws_omega_windowed_phase", sinusoid),
    ] {
        compare(preset, &layout, &params, 6000, torque);
    }
}
