//! Shape functions (SPEC §3): `θ = h(σ)` from a few shape parameters to every joint,
//! with the analytic Jacobian `J = ∂h/∂σ` that maps joint torques to shape forces.

/// A shape function `h: R^M → R^N`.
pub trait ShapeFunction {
    /// N, the joints.
    fn joint_count(&self) -> usize;
    /// M, the shape parameters.
    fn param_count(&self) -> usize;
    /// `h(σ)` into `joints_out` (length N).
    fn value(&self, sigma: &[f64], joints_out: &mut [f64]);
    /// `∂h/∂σ` into `jacobian_out`, row-major N × M (`[i * M + j] = ∂h_i/∂σ_j`).
    fn jacobian(&self, sigma: &[f64], jacobian_out: &mut [f64]);
}

/// Shape forces `F = Jᵀ·τ` (length M) from a row-major N × M Jacobian.
pub fn shape_forces(jacobian: &[f64], torques: &[f64], forces_out: &mut [f64]) {
    let m = forces_out.len();
    forces_out.fill(0.0);
    for (row, &tau) in jacobian.chunks_exact(m).zip(torques) {
        for (f, &j) in forces_out.iter_mut().zip(row) {
            *f += j * tau;
        }
    }
}

/// Central finite-difference Jacobian of `h` at `sigma` (tests, and a check for new
/// shape functions), row-major N × M.
pub fn numeric_jacobian(h: &dyn ShapeFunction, sigma: &[f64], step: f64) -> Vec<f64> {
    let (n, m) = (h.joint_count(), h.param_count());
    let mut out = vec![0.0; n * m];
    let (mut plus, mut minus) = (vec![0.0; n], vec![0.0; n]);
    let mut s = sigma.to_vec();
    for j in 0..m {
        s[j] = sigma[j] + step;
        h.value(&s, &mut plus);
        s[j] = sigma[j] - step;
        h.value(&s, &mut minus);
        s[j] = sigma[j];
        for i in 0..n {
            out[i * m + j] = (plus[i] - minus[i]) / (2.0 * step);
        }
    }
    out
}
