//! Least-squares fit of a sinusoid of known frequency: x(t) ≈ c + R·sin(ω t + φ).

/// Offset, amplitude, phase and residual RMS of the best fit.
#[derive(Debug, Clone, Copy)]
pub struct SineFit {
    pub offset: f64,
    pub amplitude: f64,
    pub phase: f64,
    pub rms_residual: f64,
}

pub fn fit_sine(t: &[f64], x: &[f64], omega: f64) -> SineFit {
    // Normal equations for the basis [1, sin ωt, cos ωt].
    let mut ata = [[0.0f64; 3]; 3];
    let mut atb = [0.0f64; 3];
    for (&ti, &xi) in t.iter().zip(x) {
        let b = [1.0, (omega * ti).sin(), (omega * ti).cos()];
        for r in 0..3 {
            atb[r] += b[r] * xi;
            for c in 0..3 {
                ata[r][c] += b[r] * b[c];
            }
        }
    }
    let m = nalgebra::Matrix3::from_fn(|r, c| ata[r][c]);
    let v = nalgebra::Vector3::from_column_slice(&atb);
    let sol = m
        .lu()
        .solve(&v)
        .expect("well-posed fit (span covers a period)");
    let (c, a, b) = (sol[0], sol[1], sol[2]);
    let mut ss = 0.0;
    for (&ti, &xi) in t.iter().zip(x) {
        let e = xi - (c + a * (omega * ti).sin() + b * (omega * ti).cos());
        ss += e * e;
    }
    SineFit {
        offset: c,
        amplitude: a.hypot(b),
        phase: b.atan2(a),
        rms_residual: (ss / t.len() as f64).sqrt(),
    }
}

/// `a − b` wrapped to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let two_pi = std::f64::consts::TAU;
    let mut x = a % two_pi;
    if x <= -std::f64::consts::PI {
        x += two_pi;
    } else if x > std::f64::consts::PI {
        x -= two_pi;
    }
    x
}
