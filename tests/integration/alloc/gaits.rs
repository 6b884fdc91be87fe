//! The gait selector and the failsafe allocate nothing per cycle, also when they
//! refuse a request: proved with a counting global allocator (this test binary only).

use snaked::gait::{BodyLayout, GaitKind, GaitSelector, GaitTable, ParamPatch, Plane};
use snaked::module::MODULE_MAX_SPEED_RAD_S;
use snaked::safety::failsafe::{Event, Failsafe, FailsafeConfig, Health, Output};

use crate::support::counting_alloc;
use counting_alloc::allocations;

/// Allocations made by this thread while running `f`.
fn allocations_in(f: impl FnOnce()) -> u64 {
    let before = allocations();
    f();
    allocations() - before
}

#[test]
fn selector_and_failsafe_cycles_do_not_allocate() {
    let layout = BodyLayout::alternating(18, Plane::Lateral, 0.064);
    let mut sel = GaitSelector::new(
        layout,
        GaitTable::default(),
        GaitKind::Slithering,
        2.0,
        MODULE_MAX_SPEED_RAD_S,
    );
    let mut fs = Failsafe::new(FailsafeConfig::default());
    let (mut pos, mut vel) = (vec![0.0; 18], vec![0.0; 18]);
    let measured = vec![0.3; 18];
    let healthy = Health {
        oldest_feedback_age_s: 0.001,
        non_finite: false,
    };
    let stale = Health {
        oldest_feedback_age_s: 1.0,
        non_finite: false,
    };
    let good = ParamPatch {
        amplitude_lat_rad: Some(0.6),
        ..ParamPatch::default()
    };
    let bad = ParamPatch {
        temporal_freq_rad_s: Some(9.0),
        ..ParamPatch::default()
    };
    let unused = ParamPatch {
        helix_radius_m: Some(0.2),
        ..ParamPatch::default()
    };

    let n = allocations_in(|| {
        let mut t = 0.0;
        for k in 0..6000 {
            t += 0.001;
            let health = if (3000..3100).contains(&k) {
                stale
            } else {
                healthy
            };
            match fs.update(t, &health) {
                Output::Resync => {
                    sel.resync(&measured, t);
                    fs.resynced(t);
                }
                Output::Run => sel.update(t, &mut pos, &mut vel),
                _ => {}
            }
            match k {
                500 => sel.set_gait(GaitKind::Sidewinding, t),
                700 => sel.set_gait(GaitKind::RollingHelix, t), // mid-blend
                900..=915 => sel.set_gait(GaitKind::ALL[k % 6], t), // overflow the stack
                1000 => assert!(sel.set_params(GaitKind::RollingHelix, &bad, t).is_err()),
                1001 => assert!(sel.set_params(GaitKind::Slithering, &unused, t).is_err()),
                1002 => sel.set_params(GaitKind::Slithering, &good, t).unwrap(),
                1003 => assert!(sel.set_blend_time(100.0).is_err()),
                1004 => sel.set_blend_time(1.0).unwrap(),
                3200 => {
                    let _ = fs.request(t, Event::Arm);
                }
                4000 => fs.request(t, Event::EStop).unwrap(),
                4001 => assert!(fs.request(t, Event::Hold).is_err()),
                4002 => fs.request(t, Event::Arm).unwrap(),
                5000 => fs.request(t, Event::Shutdown).unwrap(),
                _ => {}
            }
        }
    });
    assert_eq!(n, 0, "allocations on the per-cycle path");
    // The counter does count.
    assert!(allocations_in(|| drop(std::hint::black_box(vec![1u8; 16]))) > 0);
    assert!(fs.is_finished());
    assert!(pos.iter().all(|p| p.is_finite()));
}
