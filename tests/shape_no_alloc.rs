//! Every slithering controller's step allocates nothing, with torques coming in,
//! windows being born at the head and dropped at the tail: proved with a counting
//! global allocator (this test binary only).

use snaked::gait::{BodyLayout, GaitKind, GaitParams, Plane};
use snaked::shape::{Measured, SLITHERING_CONTROLLERS, slithering_controller};

#[path = "support/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations;

#[test]
fn no_slithering_controller_allocates_per_step() {
    // The counter works: an allocation is seen.
    let before = allocations();
    let v = std::hint::black_box(vec![1u8; 16]);
    assert!(allocations() > before && v.len() == 16);
    let n = 18;
    let layout = BodyLayout::alternating(n, Plane::Lateral, 0.064);
    let params = GaitParams::default_for(GaitKind::Slithering);
    for name in SLITHERING_CONTROLLERS {
        let mut c = slithering_controller(name, &layout, &params).unwrap();
        let (pos, mut tau, mut out) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        // Warm up (first step sizes nothing, but keep it out of the count anyway).
        c.step(
            0.0,
            &Measured {
                position_rad: &pos,
                torque_nm: &tau,
            },
            &mut out,
        );
        let before = allocations();
        // 8 s: more than a wave period, so windows are born and dropped.
        for k in 1..8000 {
            let t = k as f64 * 1e-3;
            c.step(
                t,
                &Measured {
                    position_rad: &pos,
                    torque_nm: &tau,
                },
                &mut out,
            );
            for (i, x) in tau.iter_mut().enumerate() {
                *x = -3.0 * out[i].signum() * if (k / 500 + i) % 3 == 0 { 1.0 } else { 0.0 };
            }
            let mut sink = 0.0;
            c.for_each_signal(&mut |_, v| sink += v);
            assert!(sink.is_finite());
        }
        let allocated = allocations() - before;
        assert_eq!(
            allocated, 0,
            "{name} allocated {allocated} times in 8000 steps"
        );
    }
}
