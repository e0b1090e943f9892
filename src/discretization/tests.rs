//! The nodes, placed elements and bases against what they are built from.

use super::*;
use crate::mesh::MeshKind;
use crate::scene::{SurfaceParameters, five_piece};

#[test]
fn linear_basis_functions_interpolate_at_their_nodes() {
    let scene = five_piece(SurfaceParameters::default()).unwrap();
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
    let d = Discretization::new(&scene, &mesh, Method::linear(1.0 / 6.0).unwrap()).unwrap();
    assert_eq!(d.dof(), 3 * mesh.len());
    for j in 0..d.element_count() {
        for (l, basis) in d.basis(j).iter().enumerate() {
            for m in 0..3 {
                let node = d.node(3 * j + m).position;
                let value = basis.eval(d.placed(j).frame.to_plane(node));
                let want = if l == m { 1.0 } else { 0.0 };
                assert!((value - want).abs() < 1e-13, "element {j} basis {l} node {m}: {value}");
            }
        }
        // The three basis functions sum to 1 (they interpolate constants).
        let q = DVec2::new(0.1, -0.05);
        let sum: f64 = d.basis(j).iter().map(|b| b.eval(q)).sum();
        assert!((sum - 1.0).abs() < 1e-13);
    }
}

#[test]
fn a_node_reads_its_own_face_reflectivity() {
    let mut scene = five_piece(SurfaceParameters::default()).unwrap();
    for (k, face) in scene.faces.iter_mut().enumerate() {
        face.rho = 0.1 * k as f64;
    }
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 1).unwrap();
    for method in [Method::Centroid, Method::linear(1.0 / 6.0).unwrap()] {
        let d = Discretization::new(&scene, &mesh, method).unwrap();
        for i in 0..d.dof() {
            let node = d.node(i);
            assert_eq!(d.node_rho(i), node.rho, "{method:?} node {i}");
            assert_eq!(node.rho, scene.faces[node.face()].rho, "{method:?} node {i}");
        }
    }
}

#[test]
fn centroid_nodes_are_centroids_and_alpha_is_checked() {
    let scene = five_piece(SurfaceParameters::default()).unwrap();
    let mesh = Mesh::new(&scene, &MeshKind::Uniform, 0).unwrap();
    let d = Discretization::new(&scene, &mesh, Method::Centroid).unwrap();
    for (node, e) in d.nodes().zip(mesh.elements()) {
        assert!((node.position - e.centroid()).length() < 1e-15);
    }
    // An element is placed from the mesh's element and its face's frame, not kept.
    assert!(std::mem::size_of::<Node>() <= 64);
    assert_eq!(d.element_count(), mesh.len());
    for (j, e) in mesh.elements().iter().enumerate() {
        let (placed, face) = (d.placed(j), &scene.faces[e.face].frame);
        let frame = face.with_origin(e.centroid());
        assert_eq!((placed.frame, placed.face(), d.face_of(j)), (frame, e.face, e.face));
        assert_eq!(placed.local, e.vertices.map(|v| frame.to_plane(v)));
        let unit = placed.unit;
        assert_eq!(unit, crate::geometry::power_of_two_unit(far_field::radius(&placed.local)));
        assert_eq!(placed.scaled(), placed.local.map(|v| v * unit));
    }
    // Its basis is the constant 1 on every element, kept once, not per element.
    assert!(d.bases.is_empty());
    for j in 0..d.element_count() {
        let q = DVec2::new(0.3, -0.2);
        assert_eq!(d.basis(j).map(|b| b.eval(q)), [1.0, 0.0, 0.0]);
    }
    for alpha in [-0.1, 1.0 / 3.0, f64::NAN] {
        assert!(matches!(Method::linear(alpha), Err(Error::InvalidAlpha { .. })));
    }
}
