//! A field's windows sampled at the lateral joints: the weights and their integrals
//! from the head. Sampled once when the windows change, they turn a step's evaluations
//! of the shape into matrix-vector products.

use nalgebra::DMatrixView;

use super::window_set::{EdgeColumns, WindowSet};

/// Rows: lateral joints; columns: windows (column-major).
#[derive(Debug, Clone)]
pub(super) struct JointSamples {
    /// The joints' arc lengths.
    s: Vec<f64>,
    rows: usize,
    cols: usize,
    edges: EdgeColumns,
    weight: Vec<f64>,
    integral: Vec<f64>,
    /// Each window's mean weight over the joints.
    mean: Vec<f64>,
}

impl JointSamples {
    /// For joints at arc lengths `s` and up to `windows` windows.
    pub fn new(s: &[f64], windows: usize) -> Self {
        let (rows, cells) = (s.len(), s.len() * windows);
        Self {
            s: s.to_vec(),
            rows,
            cols: 0,
            edges: EdgeColumns::new(rows),
            weight: Vec::with_capacity(cells),
            integral: Vec::with_capacity(cells),
            mean: Vec::with_capacity(windows),
        }
    }

    /// Samples `set` at the joints (no allocation within the capacity).
    pub fn fill(&mut self, set: &WindowSet) {
        let (rows, cols) = (self.rows, set.windows().len());
        self.cols = cols;
        // Every cell is written below.
        self.weight.resize(rows * cols, 0.0);
        self.integral.resize(rows * cols, 0.0);
        let (weight, integral) = (&mut self.weight, &mut self.integral);
        set.sample_columns(&self.s, &mut self.edges, weight, integral);
        self.mean.clear();
        let n = rows.max(1) as f64;
        let columns = self.weight.chunks_exact(rows.max(1)).take(cols);
        self.mean.extend(columns.map(|c| c.iter().sum::<f64>() / n));
        self.mean.resize(cols, 0.0); // no joints
    }

    fn view<'a>(&self, v: &'a [f64]) -> DMatrixView<'a, f64> {
        DMatrixView::from_slice(v, self.rows, self.cols)
    }

    /// `w_j(s_i)`.
    pub fn weight(&self) -> DMatrixView<'_, f64> {
        self.view(&self.weight)
    }

    /// `∫₀^{s_i} w_j`.
    pub fn integral(&self) -> DMatrixView<'_, f64> {
        self.view(&self.integral)
    }

    /// Window `j`'s weights and integrals at the joints.
    pub fn column(&self, j: usize) -> (&[f64], &[f64]) {
        let at = j * self.rows..(j + 1) * self.rows;
        (&self.weight[at.clone()], &self.integral[at])
    }

    /// Each window's mean weight over the joints.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }
}
