//! The pair plan (ARCHITECTURE.md): for every (collocation node, element) pair, decide once what the
//! collocation integral (4.1) needs: nothing, the whole element, or the exactly visible part.
//!
//! Work is organised per (node, face): the node's [`FaceView`] of a face holds the half-plane left
//! by the node's tangent plane (when the face straddles it) and the shadows of the occluders that
//! can lie between the node's face and this one, centrally projected from the node onto the face's
//! plane. Each element of the face is then classified against the view ([`PairPlanner::visible`]),
//! or a run of them at once by their box ([`PairPlanner::visible_in_box`]): no clip and no shadow
//! means every element is fully visible, without per-element work.
//!
//! Shadows are convex (occluders are split into convex pieces; a convex solid among them casts
//! one shadow, the window's part in its cone from the node), and the visible part of an element
//! is the element clipped by the half-plane minus each shadow, kept as disjoint convex pieces: exact
//! up to rounding (paper sec. 2.7: any O(h) error here destroys the convergence rates). A view keeps
//! no shadow that another of its shadows holds (a building's far side behind its near side), which
//! changes no visible part.
//! Candidate occluders of a view are those that may reach into the pyramid with apex at the node
//! over the face's visible window, in front of both faces. Scenes of more than 512 faces find
//! them in an R*-tree over the occluders' bounding boxes; smaller ones filter a table of the
//! occluders between each pair of faces (built with the tree). A face covered by one shadow is
//! hidden, and the search stops. So a scene in which no face can come between two others never
//! runs shadow code, and a scene of thousands of faces does not test every occluder for every
//! pair ([`Acceleration`]).

mod cluster_candidates;
mod face_view;
#[cfg(test)]
pub(crate) use face_view::PLANE_TOLERANCE;
mod hiders;
mod occluders;
mod occlusion_cube;
mod part_view;
mod planner;
mod projection;
mod row;
mod seen_faces;
mod shaft;
mod solids;
mod stats;
mod view;
mod visible_part;

pub use cluster_candidates::ClusterCandidates;
pub use hiders::RecentHiders;
pub use occluders::{Acceleration, Occluder, OccluderUnit};
pub use occlusion_cube::OcclusionCube;
pub use part_view::Caster;
pub use planner::PairPlanner;
pub use row::{ElementBoxes, FaceSight, KeptViews, PartSight, Viewer, Views, by_face};
pub use seen_faces::{FaceHierarchy, FaceSet, SightCount};
pub use shaft::Shaft;
pub use stats::PairStats;
pub use view::{FaceView, Shadows, SkipReason, Visibility};

#[cfg(test)]
mod boundary_tests;
#[cfg(test)]
mod tests;
