//! Cost of one step of the slithering controllers (torques in, set-points out) for
//! N = 18 and how it grows up to N = 1024 modules.
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use snaked::controller_interface::Tick;
use snaked::controller_interface::registry::{BuildContext, Selection, build};
use snaked::controller_interface::testing::{ObservationBuf, engage_at};
use snaked::controllers::REGISTRY;
use snaked::gait::{BodyLayout, GaitKind, GaitParams, Plane};

fn shape_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("shape_step");
    group.sample_size(30);
    let params = GaitParams::default_for(GaitKind::Slithering);
    for name in [
        "open_loop",
        "a_ws_omega",
        "a_ws_omega_central",
        "a_ws_omega_per_joint",
        "cpg",
    ] {
        for n in [18usize, 64, 256, 1024] {
            if name == "a_ws_omega_per_joint" && n > 256 {
                continue; // O(N²): one parameter per joint, each felt along the body
            }
            let layout = BodyLayout::alternating(n, Plane::Lateral, 0.064);
            let ctx = BuildContext {
                gait: GaitKind::Slithering,
                layout: &layout,
                params: &params,
            };
            let mut ctl = build(REGISTRY, &Selection::named(name), &ctx)
                .expect("a registered name")
                .controller;
            engage_at(ctl.as_mut(), &layout, &params, 0.0);
            let buf = ObservationBuf::new(n);
            let pos = vec![0.0; n];
            let tau: Vec<f64> = (0..n).map(|i| ((i % 7) as f64 - 3.0) * 0.8).collect();
            let mut out = vec![0.0; n];
            let mut t = 0.0;
            group.bench_function(BenchmarkId::new(name, n), |b| {
                b.iter(|| {
                    t += 1e-3;
                    let tick = Tick { t_s: t, dt_s: 1e-3 };
                    ctl.step(tick, &buf.observe(&pos, &tau), &mut out);
                })
            });
        }
    }
    group.finish();
}

// No plots: criterion's plotters backend finds no font once plotters' `ab_glyph`
// feature (the lab's PNGs) is on; the figures are the printed estimates.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = shape_step
}
criterion_main!(benches);
