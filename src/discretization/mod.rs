//! Collocation schemes (paper sec. 2.1 and 2.7): the nodes, and each element's basis functions as
//! affine functions of the point in the element's local frame.
//!
//! - Centroid method: one node per element at its centroid (2.5), basis 1 on the element.
//! - Piecewise linear collocation with parameter α (2.9)–(2.12): node k of an element is
//!   `α (v1 + v2 + v3) + (1 - 3α) v_k`, the image of the paper's nodes q_i under m_k, and its basis
//!   function is `(λ_k - α) / (1 - 3α)` with λ_k the barycentric coordinate of vertex k.

use std::fmt;
use std::sync::Arc;

use glam::{DVec2, DVec3};
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::geometry::PlaneFrame;
use crate::kernels::{Affine2, far_field};
use crate::mesh::{Element, Mesh};
use crate::scene::Scene;
use crate::visibility::Viewer;

crate::vocabulary::named_options! {
    /// The collocation methods by name; [`Method`] carries the linear method's α.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub enum MethodName as "method" {
        /// Piecewise constant, nodes at the centroids (sec. 2.4)
        Centroid = "centroid",
        /// Piecewise linear, three nodes per element at parameter alpha (sec. 2.5)
        Linear = "linear",
    }
}

/// The collocation method.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Method {
    /// Piecewise constant, nodes at the centroids (sec. 2.4).
    Centroid,
    /// Piecewise linear with interpolation parameter α in [0, 1/3) (sec. 2.5).
    Linear {
        /// The parameter α of (2.9).
        alpha: f64,
    },
}

impl Method {
    /// The paper's α = 1/6.
    pub const PAPER_ALPHA: f64 = 1.0 / 6.0;

    /// Piecewise linear collocation; α must lie in [0, 1/3).
    pub fn linear(alpha: f64) -> Result<Self> {
        if !(alpha.is_finite() && (0.0..1.0 / 3.0).contains(&alpha)) {
            return Err(Error::InvalidAlpha { alpha });
        }
        Ok(Self::Linear { alpha })
    }

    /// Nodes (and basis functions) per element: 1 or 3.
    pub fn nodes_per_element(&self) -> usize {
        match self {
            Self::Centroid => 1,
            Self::Linear { .. } => 3,
        }
    }

    /// The method named `name`, with α for the linear method (the paper's 1/6 where `alpha`
    /// is `None`); α given to the centroid method is refused.
    pub fn named(name: MethodName, alpha: Option<f64>) -> Result<Self> {
        match (name, alpha) {
            (MethodName::Centroid, None) => Ok(Self::Centroid),
            (MethodName::Centroid, Some(alpha)) => Err(Error::InvalidParameter {
                name: "alpha",
                value: alpha.to_string(),
                reason: "alpha belongs to the linear method".into(),
            }),
            (MethodName::Linear, alpha) => Self::linear(alpha.unwrap_or(Self::PAPER_ALPHA)),
        }
    }

    /// The method's name.
    pub fn kind(&self) -> MethodName {
        match self {
            Self::Centroid => MethodName::Centroid,
            Self::Linear { .. } => MethodName::Linear,
        }
    }

    /// Command-line name.
    pub fn name(&self) -> &'static str {
        self.kind().name()
    }

    /// α for the linear method.
    pub fn alpha(&self) -> Option<f64> {
        match self {
            Self::Centroid => None,
            Self::Linear { alpha } => Some(*alpha),
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Centroid => f.write_str("centroid"),
            Self::Linear { alpha } => write!(f, "linear (alpha = {alpha})"),
        }
    }
}

/// A collocation node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    /// Position.
    pub position: DVec3,
    /// Unit normal of its face.
    pub normal: DVec3,
    /// Reflectivity at the node.
    pub rho: f64,
    /// Face it lies on ([`Node::face`]).
    face: u32,
    /// Element it belongs to ([`Node::element`]).
    element: u32,
}

impl Node {
    /// A node at `position` of element `element` on face `face`, whose unit normal and
    /// reflectivity are `normal` and `rho`.
    pub fn new(position: DVec3, normal: DVec3, face: usize, element: usize, rho: f64) -> Self {
        let index = |i: usize| u32::try_from(i).expect("fewer than 2^32 faces and elements");
        Self { position, normal, rho, face: index(face), element: index(element) }
    }

    /// Face it lies on.
    pub fn face(&self) -> usize {
        self.face as usize
    }

    /// Element it belongs to.
    pub fn element(&self) -> usize {
        self.element as usize
    }

    /// The node as a point that looks at the scene (the pair plan's rows).
    pub fn viewer(&self) -> Viewer {
        Viewer { position: self.position, normal: self.normal, face: self.face(), rho: self.rho }
    }
}

/// An element as the kernels see it, in its own frame: origin at its centroid, axes of its
/// face. It is made from the mesh's element and its face's frame when asked for
/// ([`Discretization::placed`]), not kept: a record an element would be about twice the mesh's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    /// Centroid, the origin of the local frame.
    pub centroid: DVec3,
    /// Its local frame (origin = centroid).
    pub frame: PlaneFrame,
    /// Vertices in the local frame's 2-D coordinates (counter-clockwise).
    pub local: [DVec2; 3],
    /// Its centroid in the face frame's 2-D coordinates.
    pub centroid_in_face: DVec2,
    /// The element's unit of length: a power of two near its radius, so that scaling by it is
    /// exact. The kernels integrate in these units, where no square or fourth power of a length
    /// under- or overflows, whatever the scene's unit (G dS is invariant under scaling).
    pub unit: f64,
    /// Radius of [`Placed::scaled`] about the centroid ([`far_field::radius`]).
    pub scaled_radius: f64,
    /// Whether the closed forms cancel on it ([`far_field::is_thin`]).
    pub thin: bool,
    /// Face index.
    face: u32,
}

impl Placed {
    /// Element `e` on a face whose frame is `face`.
    fn new(e: &Element, face: &PlaneFrame) -> Self {
        let centroid = e.centroid();
        let frame = face.with_origin(centroid);
        let local = e.vertices.map(|v| frame.to_plane(v));
        let unit = crate::geometry::power_of_two_unit(far_field::radius(&local));
        Self {
            centroid,
            frame,
            local,
            centroid_in_face: face.to_plane(centroid),
            unit,
            scaled_radius: far_field::radius(&local.map(|v| v * unit)),
            thin: far_field::is_thin(&local),
            face: u32::try_from(e.face).expect("fewer than 2^32 faces"),
        }
    }

    /// The face it lies on.
    pub fn face(&self) -> usize {
        self.face as usize
    }

    /// Vertices in the local frame's 2-D coordinates and the element's units: `local` times
    /// `unit`, where the kernels integrate.
    pub fn scaled(&self) -> [DVec2; 3] {
        self.local.map(|v| v * self.unit)
    }

    /// A point of the face frame's 2-D coordinates in the element's local coordinates and units
    /// (those of [`Placed::scaled`], where the kernels integrate).
    pub fn to_scaled(&self, q: DVec2) -> DVec2 {
        (q - self.centroid_in_face) * self.unit
    }
}

/// Nodes and basis functions of a mesh under a collocation method.
#[derive(Clone, Debug)]
pub struct Discretization {
    /// The method.
    pub method: Method,
    /// The faces' frames, whose axes the elements' frames share and whose normals are the
    /// nodes'.
    face_frames: Vec<PlaneFrame>,
    /// The faces' reflectivities, the nodes'.
    face_rho: Vec<f64>,
    /// The mesh's elements, shared with it and not copied: the vertices that the local
    /// coordinates are made from ([`Discretization::placed`]).
    mesh: Arc<[Element]>,
    /// The linear method's basis functions per element, in the element's local frame; none
    /// for the centroid method, whose one basis function is 1 on every element
    /// ([`Discretization::basis`]).
    bases: Vec<[Affine2; 3]>,
}

/// The centroid method's basis on every element: the constant 1 (the others unused).
const CONSTANT_BASIS: [Affine2; 3] = [Affine2::ONE, Affine2::ZERO, Affine2::ZERO];

impl Discretization {
    /// Nodes and bases of `mesh` (on `scene`) for `method`.
    pub fn new(scene: &Scene, mesh: &Mesh, method: Method) -> Result<Self> {
        if let Method::Linear { alpha } = method {
            Method::linear(alpha)?;
        }
        let bases = match method {
            Method::Centroid => Vec::new(),
            Method::Linear { alpha } => (mesh.elements().iter())
                .map(|e| linear_basis(&Placed::new(e, &scene.faces[e.face].frame).local, alpha))
                .collect(),
        };
        let face_frames = scene.faces.iter().map(|f| f.frame).collect();
        let face_rho = scene.faces.iter().map(|f| f.rho).collect();
        let mesh = mesh.shared_elements();
        Ok(Self { method, face_frames, face_rho, mesh, bases })
    }

    /// Node `i`; for the linear method node `3j + l` belongs to basis function l of element j.
    /// Made from its element and face when asked for, not kept (64 bytes a node).
    pub fn node(&self, i: usize) -> Node {
        let per = self.method.nodes_per_element();
        let (j, l) = (i / per, i % per);
        let e = &self.mesh[j];
        let position = match self.method {
            Method::Centroid => e.centroid(),
            Method::Linear { alpha } => {
                let sum = e.vertices[0] + e.vertices[1] + e.vertices[2];
                sum * alpha + e.vertices[l] * (1.0 - 3.0 * alpha)
            }
        };
        Node::new(position, self.face_frames[e.face].normal, e.face, j, self.face_rho[e.face])
    }

    /// The reflectivity at node `i` (its face's), without making the node.
    pub fn node_rho(&self, i: usize) -> f64 {
        self.face_rho[self.mesh[i / self.method.nodes_per_element()].face]
    }

    /// Every node, in order.
    pub fn nodes(&self) -> impl ExactSizeIterator<Item = Node> + '_ {
        (0..self.dof()).map(|i| self.node(i))
    }

    /// Every node, in order, for the threads.
    pub fn par_nodes(&self) -> impl IndexedParallelIterator<Item = Node> + '_ {
        (0..self.dof()).into_par_iter().map(|i| self.node(i))
    }

    /// Element `j` with its local frame and what the kernels read of it.
    pub fn placed(&self, j: usize) -> Placed {
        let e = &self.mesh[j];
        Placed::new(e, &self.face_frames[e.face])
    }

    /// The face element `j` lies on.
    pub fn face_of(&self, j: usize) -> usize {
        self.mesh[j].face
    }

    /// The centroid of element `j` in its face frame's 2-D coordinates.
    pub fn centroid_in_face(&self, j: usize) -> DVec2 {
        self.placed(j).centroid_in_face
    }

    /// The vertices of element `j` in its face frame's 2-D coordinates.
    pub fn in_face(&self, j: usize) -> [DVec2; 3] {
        let placed = self.placed(j);
        placed.local.map(|v| v + placed.centroid_in_face)
    }

    /// Number of unknowns d_n (n or 3n).
    pub fn dof(&self) -> usize {
        self.mesh.len() * self.method.nodes_per_element()
    }

    /// Number of elements n.
    pub fn element_count(&self) -> usize {
        self.mesh.len()
    }

    /// The basis functions on element `j` (one or three used), in its local frame.
    pub fn basis(&self, j: usize) -> &[Affine2; 3] {
        match self.method {
            Method::Centroid => &CONSTANT_BASIS,
            Method::Linear { .. } => &self.bases[j],
        }
    }
}

/// `(λ_k - α) / (1 - 3α)`, k = 0, 1, 2, as affine functions on the triangle `v` (counter-clockwise).
fn linear_basis(v: &[DVec2; 3], alpha: f64) -> [Affine2; 3] {
    let twice_area = (v[1] - v[0]).perp_dot(v[2] - v[0]);
    let scale = 1.0 / (1.0 - 3.0 * alpha);
    [0, 1, 2].map(|k| {
        // λ_k(X) = (q - p) × (X - p) / (2 area) over the opposite side p -> q.
        let (p, q) = (v[(k + 1) % 3], v[(k + 2) % 3]);
        let d = q - p;
        Affine2 {
            c0: (d.perp_dot(-p) / twice_area - alpha) * scale,
            cx: -d.y / twice_area * scale,
            cy: d.x / twice_area * scale,
        }
    })
}

#[cfg(test)]
mod tests;
