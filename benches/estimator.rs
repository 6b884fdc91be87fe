//! Cost of one update of the virtual-chassis estimator (joint angles and IMUs in, the
//! body estimate out) for N = 18 modules on a bent, moving body.
use criterion::{Criterion, criterion_group, criterion_main};
use snaked::controller_interface::{BodyEstimate, Estimator, Imu, Observation};
use snaked::estimation::{DEFAULT_TIME_CONSTANT_S, VirtualChassisEstimator};
use snaked::gait::{BodyLayout, Plane};

fn estimator(c: &mut Criterion) {
    let n = 18;
    let layout = BodyLayout::alternating(n, Plane::Lateral, 0.064);
    let mut e = VirtualChassisEstimator::new(layout, DEFAULT_TIME_CONSTANT_S);
    let pos: Vec<f64> = (0..n).map(|i| 0.6 * (i as f64 * 0.9).sin()).collect();
    let imu: Vec<Imu> = (0..n)
        .map(|i| Imu {
            accel_m_s2: [0.1, 0.05 * i as f64, 9.8],
            gyro_rad_s: [0.01, -0.02, 0.3],
        })
        .collect();
    let zeros = vec![0.0; n];
    let previous = BodyEstimate::default();
    let mut body = BodyEstimate::default();
    let mut t = 0.0;
    c.bench_function("virtual_chassis_update_18", |b| {
        b.iter(|| {
            t += 1e-3;
            let obs = Observation {
                position_rad: &pos,
                velocity_rad_s: &zeros,
                torque_nm: &zeros,
                imu: &imu,
                body: &previous,
            };
            e.update(t, &obs, &mut body);
            std::hint::black_box(&body);
        })
    });
}

criterion_group!(benches, estimator);
criterion_main!(benches);
