//! The view factor matrix ([`ViewFactors`]): its sparse rows and what is read from them (entries,
//! row sums, reciprocity, face-to-face factors).

use crate::mesh::Mesh;

/// The view factor matrix (its non-zero entries, row by row: memory follows what is seen, not
/// n²) and its checks.
#[derive(Clone, Debug)]
pub struct ViewFactors {
    /// Where row i's entries start in `columns` and `values`, and where the last row's end
    /// (n + 1 offsets).
    pub row_starts: Vec<usize>,
    /// Column j of each non-zero F_ij, increasing within a row.
    pub columns: Vec<u32>,
    /// F_ij of each entry.
    pub values: Vec<f64>,
    /// Element areas A_i.
    pub areas: Vec<f64>,
    /// Largest estimated error of an entry F_ij: the sum of its patches' estimates (the
    /// difference of two Gauss orders, the error of the coarser one where the finer one's value
    /// is kept; or Bailey's estimate from the last three tanh-sinh levels). Above the tolerance
    /// only where patches reached [`MAX_SPLITS`](super::options::MAX_SPLITS).
    pub error_estimate: f64,
    /// Point-to-element integrals evaluated.
    pub evaluations: u64,
    /// Whether F_ij and F_ji were integrated each ([`ViewFactorOptions::each_direction`]);
    /// otherwise reciprocity holds by construction, to rounding.
    ///
    /// [`ViewFactorOptions::each_direction`]: super::options::ViewFactorOptions::each_direction
    pub each_direction: bool,
    /// Entries whose integral came out below zero by rounding, stored as zero.
    pub clamped: usize,
}

impl ViewFactors {
    /// Number of elements.
    pub fn len(&self) -> usize {
        self.areas.len()
    }

    /// Entries that are not zero.
    pub fn nonzeros(&self) -> usize {
        self.values.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.areas.is_empty()
    }

    /// Row i's non-zero entries: their columns and values.
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.row_starts[i]..self.row_starts[i + 1];
        (&self.columns[range.clone()], &self.values[range])
    }

    /// F_ij.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        let (columns, values) = self.row(i);
        columns.binary_search(&(j as u32)).map_or(0.0, |k| values[k])
    }

    /// F as a dense row-major n x n matrix (n² values: for small scenes and dense outputs).
    pub fn to_dense(&self) -> Vec<f64> {
        let n = self.len();
        let mut dense = vec![0.0; n * n];
        for i in 0..n {
            let (columns, values) = self.row(i);
            for (&j, &v) in columns.iter().zip(values) {
                dense[i * n + j as usize] = v;
            }
        }
        dense
    }

    /// Smallest and largest row sum.
    pub fn row_sum_range(&self) -> (f64, f64) {
        (0..self.len())
            .map(|i| self.row(i).1.iter().sum::<f64>())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), s| (lo.min(s), hi.max(s)))
    }

    /// max |A_i F_ij - A_j F_ji| relative to the largest A_i F_ij: over the stored entries, as
    /// a pair with both entries zero adds nothing.
    pub fn reciprocity_error(&self) -> f64 {
        let (mut worst, mut scale) = (0.0f64, 0.0f64);
        for i in 0..self.len() {
            let (columns, values) = self.row(i);
            for (&j, &v) in columns.iter().zip(values) {
                let j = j as usize;
                let (a, b) = (self.areas[i] * v, self.areas[j] * self.get(j, i));
                worst = worst.max((a - b).abs());
                scale = scale.max(a.abs());
            }
        }
        if scale > 0.0 { worst / scale } else { 0.0 }
    }

    /// Face-to-face view factors: F_ab = (1/A_a) Σ_{i in a} A_i Σ_{j in b} F_ij.
    pub fn by_face(&self, mesh: &Mesh) -> Vec<Vec<f64>> {
        let faces = mesh.face_count();
        let mut sums = vec![vec![0.0; faces]; faces];
        let mut face_areas = vec![0.0; faces];
        for (i, e) in mesh.elements().iter().enumerate() {
            face_areas[e.face] += self.areas[i];
            let (columns, values) = self.row(i);
            for (&j, &v) in columns.iter().zip(values) {
                sums[e.face][mesh.elements()[j as usize].face] += self.areas[i] * v;
            }
        }
        for (row, area) in sums.iter_mut().zip(face_areas) {
            row.iter_mut().for_each(|s| *s /= area);
        }
        sums
    }
}
