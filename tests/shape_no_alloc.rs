//! Every slithering controller's step allocates nothing, with torques coming in,
//! windows being born at the head and dropped at the tail: proved with a counting
//! global allocator (this test binary only).
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use snaked::gait::{BodyLayout, GaitKind, GaitParams, Plane};
use snaked::shape::{Measured, SLITHERING_CONTROLLERS, slithering_controller};

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<u64> = const { Cell::new(0) };
}

fn count() {
    let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc(layout) }
    }
    unsafe fn alloc_zeroed(&self, layout: Layout) -> *mut u8 {
        count();
        unsafe { System.alloc_zeroed(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        count();
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn no_slithering_controller_allocates_per_step() {
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
        let before = ALLOCATIONS.with(Cell::get);
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
        let allocated = ALLOCATIONS.with(Cell::get) - before;
        assert_eq!(
            allocated, 0,
            "{name} allocated {allocated} times in 8000 steps"
        );
    }
}
