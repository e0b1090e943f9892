//! What a node sees, as the planner answers it: of one face a [`FaceView`] (the tangent plane's
//! clip and the occluders' [`Shadows`]), of one element of it a [`Visibility`], and for a pair
//! that contributes nothing the [`SkipReason`]. Kept apart from the planner that computes them,
//! since the row walks, the statistics and the assembly only read them.

use glam::DVec2;

use crate::geometry::{HalfPlane, bounding_box};

/// Why a pair contributes nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SkipReason {
    /// The node and the element lie in one plane: G = 0.
    SamePlane,
    /// The element is behind the node's tangent plane or the node behind the element: G <= 0.
    FacingAway,
    /// Occluders hide the whole element.
    Hidden,
    /// The node's face reflects nothing (rho = 0): its row of K is zero, u = E there.
    NotReflecting,
}

/// What a node sees of one face.
#[derive(Clone, Debug, PartialEq)]
pub enum FaceView {
    /// Nothing of the face.
    Skip(SkipReason),
    /// The face is in front of the node; parts may be clipped or shadowed.
    Visible {
        /// Half-plane (face coordinates) in front of the node's tangent plane, when the face
        /// straddles that plane.
        clip: Option<HalfPlane>,
        /// Convex shadows (face coordinates, counter-clockwise) of the occluders.
        shadows: Shadows,
    },
}

/// The convex shadows of a view (face coordinates, counter-clockwise), each with its bounding
/// box: a view serves every element of its face, and each element is tested against every
/// shadow's box first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shadows {
    polygons: Vec<Vec<DVec2>>,
    boxes: Vec<(DVec2, DVec2)>,
}

impl Shadows {
    /// Shadows with their boxes measured.
    pub fn new(polygons: Vec<Vec<DVec2>>) -> Self {
        let boxes = polygons.iter().map(|s| bounding_box(s)).collect();
        Self { polygons, boxes }
    }

    /// Shadows whose boxes are known.
    pub(super) fn with_boxes(shadows: impl Iterator<Item = (Vec<DVec2>, (DVec2, DVec2))>) -> Self {
        let (polygons, boxes) = shadows.unzip();
        Self { polygons, boxes }
    }

    /// Each shadow's bounding box, in order.
    pub fn boxes(&self) -> &[(DVec2, DVec2)] {
        &self.boxes
    }

    /// The polygons alone.
    pub fn into_polygons(self) -> Vec<Vec<DVec2>> {
        self.polygons
    }
}

impl std::ops::Deref for Shadows {
    type Target = [Vec<DVec2>];

    fn deref(&self) -> &[Vec<DVec2>] {
        &self.polygons
    }
}

impl FaceView {
    /// Whether every element of the face is fully visible.
    pub fn is_unobstructed(&self) -> bool {
        matches!(self, Self::Visible { clip: None, shadows } if shadows.is_empty())
    }
}

/// The visible part of a convex polygon (an element) under a [`FaceView`].
#[derive(Clone, Debug, PartialEq)]
pub enum Visibility {
    /// Nothing is visible, for the given reason.
    Skip(SkipReason),
    /// All of it.
    Full,
    /// Disjoint convex pieces, counter-clockwise, in face coordinates.
    Partial(Vec<Vec<DVec2>>),
}
