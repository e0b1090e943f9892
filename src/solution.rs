//! A computed solution on its mesh, as the outputs (VTK, CSV, pictures) see it: values per
//! element and at element vertices.

use crate::discretization::{Discretization, Method};
use crate::mesh::Mesh;
use crate::scene::Scene;

/// A band's solution at the nodes, for the outputs.
#[derive(Clone, Debug)]
pub struct BandValues {
    /// Index into [`crate::scene::CHANNELS`].
    pub channel: usize,
    /// u at the nodes.
    pub u: Vec<f64>,
    /// E at the nodes.
    pub emission: Vec<f64>,
}

/// An emission case's solution at the nodes, for the outputs.
#[derive(Clone, Debug)]
pub struct CaseValues {
    /// The case's name.
    pub name: String,
    /// u at the nodes.
    pub u: Vec<f64>,
    /// E at the nodes.
    pub emission: Vec<f64>,
}

/// The collocation solution u_n with the emissivity E at the nodes.
#[derive(Clone, Copy, Debug)]
pub struct SolutionField<'a> {
    /// The scene (face names, rho).
    pub scene: &'a Scene,
    /// The mesh.
    pub mesh: &'a Mesh,
    /// Nodes and method.
    pub disc: &'a Discretization,
    /// Nodal values of u_n.
    pub u: &'a [f64],
    /// E at the nodes.
    pub emission: &'a [f64],
    /// The colour bands' solutions, when solved per band (`u` is then their mean).
    pub bands: &'a [BandValues],
    /// The emission cases' solutions, when cases were solved (`u` is then their mean).
    pub cases: &'a [CaseValues],
}

impl SolutionField<'_> {
    /// u_n at the three vertices of element `j`: the element's value for the centroid method; for
    /// the linear method the affine u_n at the vertices. Basis m of (2.12) is (λ_m - α)/(1 - 3α),
    /// so at vertex k: u(v_k) = (u_k - α Σ_m u_m) / (1 - 3α).
    pub fn vertex_values(&self, j: usize) -> [f64; 3] {
        self.vertex_values_of(self.u, j)
    }

    /// The nodal values `u` (of u_n or of a band) at the three vertices of element `j`.
    pub fn vertex_values_of(&self, u: &[f64], j: usize) -> [f64; 3] {
        match self.disc.method {
            Method::Centroid => [u[j]; 3],
            Method::Linear { alpha } => {
                let u = &u[3 * j..3 * j + 3];
                let sum: f64 = u.iter().sum();
                [0, 1, 2].map(|k| (u[k] - alpha * sum) / (1.0 - 3.0 * alpha))
            }
        }
    }

    /// Mean of u_n over element `j` (its value at the centroid).
    pub fn element_value(&self, j: usize) -> f64 {
        self.element_mean(self.u, j)
    }

    /// Mean of E over the nodes of element `j`.
    pub fn element_emission(&self, j: usize) -> f64 {
        self.element_mean(self.emission, j)
    }

    /// Mean of the nodal values `v` over the nodes of element `j`.
    pub fn element_mean(&self, v: &[f64], j: usize) -> f64 {
        let per = self.disc.method.nodes_per_element();
        v[per * j..per * (j + 1)].iter().sum::<f64>() / per as f64
    }
}
