//! Cost of one control cycle (feedback in, failsafe, gait selector, commands out,
//! statistics and telemetry) over an ideal in-process plant.
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use snaked::gait::GaitKind;
use snaked::rt::harness::echo_harness;
use snaked::safety::failsafe::FailsafeConfig;

fn control_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("control_step");
    for n in [18usize, 64] {
        for gait in [GaitKind::Sidewinding, GaitKind::RollingHelix] {
            let mut h = echo_harness(n, None, gait, false, FailsafeConfig::default());
            for _ in 0..3000 {
                h.control.step(); // past start-up and the blend
            }
            group.bench_function(BenchmarkId::new(gait.name(), n), |b| {
                b.iter(|| h.control.step())
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
    targets = control_step
}
criterion_main!(benches);
