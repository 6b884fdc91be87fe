//! Every registered controller, with every preset, on every gait it runs, engages,
//! steps and reports without allocating, with torques coming in and (for windowed
//! ones) windows being born at the head and dropped at the tail, and follows a change
//! of its parameters and takes a configuration in place: proved with a
//! counting global allocator (this test binary only).

use snaked::controller_interface::TickClock;
use snaked::controller_interface::registry::{BuildContext, for_gait};
use snaked::controller_interface::report::ControllerReport;
use snaked::controller_interface::testing::{ObservationBuf, engage_at};
use snaked::controllers::REGISTRY;
use snaked::gait::{BodyLayout, GaitKind, GaitTable, Plane};

use crate::support::counting_alloc;
use counting_alloc::allocations;

#[test]
fn no_registered_controller_allocates_per_step() {
    // The counter works: an allocation is seen.
    let before = allocations();
    let v = std::hint::black_box(vec![1u8; 16]);
    assert!(allocations() > before && v.len() == 16);
    let n = 18;
    let layout = BodyLayout::alternating(n, Plane::Lateral, 0.064);
    let table = GaitTable::default();
    let mut checked = 0;
    for gait in GaitKind::ALL {
        let params = table.get(gait);
        let ctx = BuildContext {
            gait,
            layout: &layout,
            params,
        };
        for family in for_gait(REGISTRY, gait) {
            for (preset, _) in family.presets() {
                let mut built = family.build(preset, None, &ctx).expect("presets build");
                // A twin to reconfigure from (built before counting: building allocates).
                let mut twin = family.build(preset, None, &ctx).expect("presets build");
                let mut faster = *params;
                faster.temporal_freq_rad_s *= 1.2;
                let c = built.controller.as_mut();
                let (pos, mut tau, mut out) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                let buf = ObservationBuf::new(n);
                let mut report = ControllerReport::EMPTY;
                let before = allocations();
                engage_at(c, &layout, params, 0.0);
                assert!(c.accepts(params).is_ok());
                let mut clock = TickClock::default();
                // 8 s: more than a wave period, so windows are born and dropped.
                for k in 0..8000 {
                    let t = k as f64 * 1e-3;
                    // A followed change, then a configuration taken in place (issue 45);
                    // whether the controller takes them or not, nothing allocates.
                    if k == 3000 {
                        let _ = c.follow(t, &faster);
                    }
                    if k == 5000 {
                        let _ = c.reconfigure(twin.controller.as_mut());
                    }
                    c.step(clock.tick(t), &buf.observe(&pos, &tau), &mut out);
                    for (i, x) in tau.iter_mut().enumerate() {
                        let on = (k / 500 + i) % 3 == 0;
                        *x = if on { -3.0 * out[i].signum() } else { 0.0 };
                    }
                    c.report(&mut report);
                    assert!(out.iter().all(|x: &f64| x.is_finite()));
                }
                engage_at(c, &layout, params, 9.0);
                let allocated = allocations() - before;
                let name = format!("{gait:?} {}/{preset}", family.name());
                assert_eq!(allocated, 0, "{name} allocated {allocated} times");
                checked += 1;
            }
        }
    }
    assert!(checked >= 13, "every family's presets: {checked}");
}
