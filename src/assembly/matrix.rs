//! The dense collocation matrix K, stored row-major (rows are assembled in parallel).

use faer::Mat;
use rayon::prelude::*;

use super::memory::check_fits;
use crate::error::Result;

/// A dense dof × dof matrix K of (2.43), including the factor rho/π; the system is (I - K) u = E.
#[derive(Clone, Debug, PartialEq)]
pub struct CollocationMatrix {
    dof: usize,
    data: Vec<f64>,
}

impl CollocationMatrix {
    /// A zero matrix, or [`Error::TooLarge`] when it would not fit in memory.
    pub fn zeros(dof: usize) -> Result<Self> {
        check_fits((dof as f64) * (dof as f64) * 8.0, dof)?;
        Ok(Self { dof, data: vec![0.0; dof * dof] })
    }

    /// Wraps row-major data.
    pub fn from_rows(dof: usize, data: Vec<f64>) -> Self {
        assert_eq!(data.len(), dof * dof, "CollocationMatrix::from_rows: wrong length");
        Self { dof, data }
    }

    /// Number of unknowns.
    pub fn dof(&self) -> usize {
        self.dof
    }

    /// Entry (i, j).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.data[i * self.dof + j]
    }

    /// Row i.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[i * self.dof..(i + 1) * self.dof]
    }

    /// Row-major entries.
    pub fn as_slice(&self) -> &[f64] {
        &self.data
    }

    /// Parallel iterator over mutable rows.
    pub fn rows_mut(&mut self) -> rayon::slice::ChunksExactMut<'_, f64> {
        self.data.par_chunks_exact_mut(self.dof.max(1))
    }

    /// Rows `rows` as one mutable slice.
    pub fn rows_slice_mut(&mut self, rows: std::ops::Range<usize>) -> &mut [f64] {
        &mut self.data[rows.start * self.dof..rows.end * self.dof]
    }

    /// `K x`.
    pub fn apply(&self, x: &[f64]) -> Vec<f64> {
        self.data
            .par_chunks_exact(self.dof.max(1))
            .map(|row| row.iter().zip(x).map(|(a, b)| a * b).sum())
            .collect()
    }

    /// The system matrix I - K as a faer matrix.
    pub fn system_matrix(&self) -> Mat<f64> {
        Mat::from_fn(self.dof, self.dof, |i, j| {
            let k = self.data[i * self.dof + j];
            if i == j { 1.0 - k } else { -k }
        })
    }
}
