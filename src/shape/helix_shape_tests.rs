use super::*;
use crate::gait::{GaitKind, GaitParams, Serpenoid};
use crate::module::MODULE_LENGTH_M;
use crate::shape::function::numeric_jacobian;
use crate::shape::window::steepness_for_width;

fn layout() -> BodyLayout {
    BodyLayout::alternating(18, Plane::Lateral, MODULE_LENGTH_M)
}

/// The default rolling helix's amplitude and spatial frequency (rad per body length).
fn nominal() -> (f64, f64) {
    let l = layout();
    let s = Serpenoid::for_layout(
        GaitKind::RollingHelix,
        &GaitParams::default_for(GaitKind::RollingHelix),
        &l,
    );
    let w = s.wave(Plane::Dorsal);
    (w.amplitude_rad, w.spatial_freq_rad)
}

/// Three windows of about half a coil at the nominal ωS (a coil is 2π of phase).
fn half_coils(spatial_freq: f64) -> Vec<Window> {
    let half = std::f64::consts::PI / spatial_freq;
    vec![
        Window {
            a: f64::NEG_INFINITY,
            b: 0.2 + half,
        },
        Window {
            a: 0.2 + half,
            b: 0.2 + 2.0 * half,
        },
        Window {
            a: 0.2 + 2.0 * half,
            b: f64::INFINITY,
        },
    ]
}

/// One R for the whole body is the daemon's rolling helix: the same joint angles as
/// the gait's serpenoid at the same phase.
#[test]
fn one_radius_everywhere_is_the_rolling_helix_gait() {
    let l = layout();
    let (a, ws) = nominal();
    let gait = Serpenoid::for_layout(
        GaitKind::RollingHelix,
        &GaitParams::default_for(GaitKind::RollingHelix),
        &l,
    );
    let mut h = HelixShape::new(&l, &[Window::EVERYWHERE], 10.0, HelixShape::tie(a, ws));
    let (mut ours, mut theirs) = (vec![0.0; 18], vec![0.0; 18]);
    for psi in [0.0, 0.7, 2.5, -4.0] {
        h.set_phase(psi);
        h.value(&[ws], &mut ours);
        gait.evaluate(&l, psi, &mut theirs);
        for (x, y) in ours.iter().zip(&theirs) {
            assert!((x - y).abs() < 1e-12, "ψ {psi}: {ours:?} vs {theirs:?}");
        }
    }
    // R scales the amplitude and the spatial frequency together.
    assert!((ws / h.k() - a).abs() < 1e-12);
    h.set_phase(0.0);
    h.value(&[1.2 * ws], &mut ours);
    let peak = ours.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    assert!(peak <= 1.2 * a + 1e-12 && peak > 1.1 * a, "{peak} vs {a}");
}

#[test]
fn the_analytic_jacobian_matches_finite_differences() {
    let l = layout();
    let (a, ws) = nominal();
    let mut h = HelixShape::new(
        &l,
        &half_coils(ws),
        steepness_for_width(0.5 / 18.0),
        HelixShape::tie(a, ws),
    );
    h.set_phase(1.3);
    let r = [0.9 * ws, 1.15 * ws, 1.02 * ws];
    let mut analytic = vec![0.0; 18 * 3];
    h.jacobian(&r, &mut analytic);
    let numeric = numeric_jacobian(&h, &r, 1e-6);
    for (k, (x, y)) in analytic.iter().zip(&numeric).enumerate() {
        assert!(
            (x - y).abs() < 1e-6 * (1.0 + y.abs()),
            "joint {} window {}: {x} vs {y}",
            k / 3,
            k % 3
        );
    }
    // Every window reaches the joints it covers; the head's window reaches every joint
    // behind it through the phase.
    assert!(
        analytic
            .chunks(3)
            .all(|row| row[0].abs() + row[1].abs() + row[2].abs() > 0.0)
    );
}

/// Tightening a window leaves the coil ahead of it (toward the head) as it was, and
/// moves the coil behind it without a jump: the phase is the integral of R.
#[test]
fn a_tighter_window_leaves_the_head_side_and_does_not_tear_the_tail_side() {
    let l = layout();
    let (a, ws) = nominal();
    let windows = half_coils(ws);
    let h = HelixShape::new(
        &l,
        &windows,
        steepness_for_width(0.5 / 18.0),
        HelixShape::tie(a, ws),
    );
    let (mut before, mut after) = (vec![0.0; 18], vec![0.0; 18]);
    h.value(&[ws, ws, ws], &mut before);
    h.value(&[ws, 1.3 * ws, ws], &mut after);
    let start = windows[1].a;
    for (i, &s) in l.s.iter().enumerate() {
        if s < start - 0.15 {
            assert!((before[i] - after[i]).abs() < 1e-3, "joint {i} at {s}");
        }
    }
    // The phase behind the window is shifted by the window's extra R times its length,
    // continuously along the body.
    let (_, p_mid) = h.field_at(&[ws, 1.3 * ws, ws], windows[1].b + 0.1);
    let (_, p_ref) = h.field_at(&[ws, ws, ws], windows[1].b + 0.1);
    let extra = 0.3 * ws * (windows[1].b - windows[1].a);
    assert!(
        (p_mid - p_ref - extra).abs() < 0.05 * extra,
        "{} vs {extra}",
        p_mid - p_ref
    );
    let mut last = h.field_at(&[ws, 1.3 * ws, ws], 0.0).1;
    for k in 1..=200 {
        let p = h.field_at(&[ws, 1.3 * ws, ws], k as f64 / 200.0).1;
        assert!(
            (p - last).abs() < 1.3 * ws / 200.0 + 1e-9,
            "a jump at {}",
            k as f64 / 200.0
        );
        last = p;
    }
}

/// The window manager anchors windows to the helix's phase crossings φ = kπ: each
/// window is half a coil, and where a window tightens its neighbours shift and it
/// shortens (the coil's half-turns come sooner).
#[test]
fn the_window_manager_cuts_the_coil_into_half_turns() {
    use crate::shape::window_manager::{Slope, WindowManager};
    let l = layout();
    let (a, ws) = nominal();
    let steep = steepness_for_width(0.5 / 18.0);
    let mut h = HelixShape::with_capacity(&l, 12, steep, HelixShape::tie(a, ws));
    let mut manager: WindowManager<f64> = WindowManager::new(18 + 9, 12);
    // Uniform R: re-anchor a few times (the windows' own edges do not change φ then).
    h.set_phase(0.4);
    for _ in 0..3 {
        let r: Vec<f64> = manager.windows().map(|w| w.payload).collect();
        let r = if r.is_empty() { vec![ws] } else { r };
        let probe = h.clone();
        manager.update(|s| probe.field_at(&r, s).1, ws, Slope::Increasing);
        h.set_windows(manager.windows().map(|w| w.window));
    }
    let windows: Vec<Window> = h.windows().to_vec();
    let half = std::f64::consts::PI / ws;
    assert!(windows.len() >= 2, "{windows:?}");
    for w in &windows[1..windows.len() - 1] {
        assert!(
            ((w.b - w.a) - half).abs() < 0.02,
            "{w:?} vs half a coil {half}"
        );
    }
    // Every edge sits where φ = kπ.
    let r = vec![ws; windows.len()];
    for w in &windows[1..] {
        let phi = h.field_at(&r, w.a).1;
        let off = (phi / std::f64::consts::PI - (phi / std::f64::consts::PI).round()).abs();
        assert!(off < 0.02, "edge at {} has φ {phi}", w.a);
    }
}
