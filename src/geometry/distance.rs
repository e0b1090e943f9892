//! Distances between convex planar polygons in space.

use glam::DVec3;

/// The distance between two convex planar polygons in space, 0 where they meet. The nearest
/// points of two convex polygons are a corner of one and a point of the other, or a point on
/// an edge of each; where an edge of one crosses the other's inside, they meet.
pub fn convex_polygons_distance(a: &[DVec3], b: &[DVec3]) -> f64 {
    let mut d = f64::INFINITY;
    for (p, q) in [(a, b), (b, a)] {
        // q's plane, found once for all of p's corners and edges.
        let plane = normal(q);
        let m = p.len();
        for k in 0..m {
            let (s0, s1) = (p[k], p[(k + 1) % m]);
            if plane.is_some_and(|n| segment_crosses(s0, s1, q, n)) {
                return 0.0;
            }
            d = d.min(point_to_polygon(s0, q, plane));
            let l = q.len();
            for k in 0..l {
                d = d.min(segment_distance((s0, s1), (q[k], q[(k + 1) % l])));
            }
        }
    }
    d
}

/// The unit normal of a planar polygon by Newell's sums (its corners counter-clockwise about
/// it), or `None` for a polygon without area.
fn normal(polygon: &[DVec3]) -> Option<DVec3> {
    let m = polygon.len();
    let n: DVec3 = (0..m).map(|k| polygon[k].cross(polygon[(k + 1) % m])).sum();
    (n.length_squared() > 0.0).then(|| n.normalize())
}

/// Whether `x`, in the plane of the convex `polygon` (normal `n`), lies inside it or on it.
fn inside(x: DVec3, polygon: &[DVec3], n: DVec3) -> bool {
    let m = polygon.len();
    (0..m).all(|k| (polygon[(k + 1) % m] - polygon[k]).cross(x - polygon[k]).dot(n) >= 0.0)
}

/// Distance from a point to a convex planar polygon with unit normal `plane` (`None`: no area).
fn point_to_polygon(v: DVec3, polygon: &[DVec3], plane: Option<DVec3>) -> f64 {
    if let Some(n) = plane {
        let h = n.dot(v - polygon[0]);
        if inside(v - n * h, polygon, n) {
            return h.abs();
        }
    }
    let m = polygon.len();
    (0..m)
        .map(|k| point_to_segment(v, polygon[k], polygon[(k + 1) % m]))
        .fold(f64::INFINITY, f64::min)
}

/// Whether the segment from `s0` to `s1` crosses the plane of the convex `polygon` (unit
/// normal `n`) strictly (its ends on opposite sides) at a point inside it.
fn segment_crosses(s0: DVec3, s1: DVec3, polygon: &[DVec3], n: DVec3) -> bool {
    let (h0, h1) = (n.dot(s0 - polygon[0]), n.dot(s1 - polygon[0]));
    if h0 * h1 >= 0.0 {
        return false;
    }
    inside(s0 + (s1 - s0) * (h0 / (h0 - h1)), polygon, n)
}

fn point_to_segment(v: DVec3, a: DVec3, b: DVec3) -> f64 {
    let ab = b - a;
    let length = ab.length_squared();
    let t = if length > 0.0 { ((v - a).dot(ab) / length).clamp(0.0, 1.0) } else { 0.0 };
    v.distance(a + ab * t)
}

/// Distance between the segments `(p0, p1)` and `(q0, q1)`: the nearest points of the two
/// lines, each clamped to its segment and the other's recomputed (Ericson, Real-Time Collision
/// Detection, 5.1.9); parallel or degenerate segments by their ends.
fn segment_distance((p0, p1): (DVec3, DVec3), (q0, q1): (DVec3, DVec3)) -> f64 {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let (c, b) = (d1.dot(r), d1.dot(d2));
    let denominator = a * e - b * b;
    if a == 0.0 || e == 0.0 || denominator <= 1e-14 * a * e {
        return point_to_segment(p0, q0, q1)
            .min(point_to_segment(p1, q0, q1))
            .min(point_to_segment(q0, p0, p1))
            .min(point_to_segment(q1, p0, p1));
    }
    let mut s = ((b * f - c * e) / denominator).clamp(0.0, 1.0);
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = (-c / a).clamp(0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = ((b - c) / a).clamp(0.0, 1.0);
    }
    (p0 + d1 * s).distance(q0 + d2 * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng, rngs::StdRng};

    fn square(z: f64, shift: DVec3) -> Vec<DVec3> {
        [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .map(|&(x, y)| DVec3::new(x, y, z) + shift)
            .collect()
    }

    #[test]
    fn known_distances_between_squares_and_triangles() {
        let base = square(0.0, DVec3::ZERO);
        assert!((convex_polygons_distance(&base, &square(2.0, DVec3::ZERO)) - 2.0).abs() < 1e-15);
        // Beside, one unit apart along x, and raised by one: sqrt(2).
        let beside = square(1.0, DVec3::new(2.0, 0.0, 0.0));
        let expected = 2f64.sqrt();
        assert!((convex_polygons_distance(&base, &beside) - expected).abs() < 1e-15);
        // Sharing an edge (a wall on a floor), and a wall standing across the floor's inside.
        let wall: Vec<DVec3> = [(1.0, 0.0, 0.0), (1.0, 1.0, 0.0), (1.0, 1.0, 1.0), (1.0, 0.0, 1.0)]
            .iter()
            .map(|&(x, y, z)| DVec3::new(x, y, z))
            .collect();
        assert_eq!(convex_polygons_distance(&base, &wall), 0.0);
        let across: Vec<DVec3> = wall.iter().map(|v| *v - DVec3::new(0.5, 0.0, 0.5)).collect();
        assert_eq!(convex_polygons_distance(&base, &across), 0.0);
        // A triangle over the square's middle, tilted: its lowest corner is nearest.
        let tilted =
            [DVec3::new(0.5, 0.5, 0.25), DVec3::new(2.0, 0.5, 3.0), DVec3::new(0.5, 2.0, 3.0)];
        assert!((convex_polygons_distance(&base, &tilted) - 0.25).abs() < 1e-15);
    }

    #[test]
    fn distances_are_the_least_over_sampled_points_of_random_triangles() {
        let mut rng = StdRng::seed_from_u64(3);
        let point = |rng: &mut StdRng| {
            DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
        };
        let sample = |t: &[DVec3; 3], u: f64, v: f64| {
            let (u, v) = if u + v > 1.0 { (1.0 - u, 1.0 - v) } else { (u, v) };
            t[0] + (t[1] - t[0]) * u + (t[2] - t[0]) * v
        };
        for _ in 0..200 {
            let a = [point(&mut rng), point(&mut rng), point(&mut rng)];
            let b = [
                point(&mut rng) + DVec3::X,
                point(&mut rng) + DVec3::X,
                point(&mut rng) + DVec3::X,
            ];
            let exact = convex_polygons_distance(&a, &b);
            let steps = 40;
            let grid: Vec<(f64, f64)> = (0..=steps)
                .flat_map(|i| {
                    (0..=steps).map(move |j| (i as f64 / steps as f64, j as f64 / steps as f64))
                })
                .collect();
            let points_b: Vec<DVec3> = grid.iter().map(|&(u, v)| sample(&b, u, v)).collect();
            let sampled = grid
                .iter()
                .map(|&(u, v)| sample(&a, u, v))
                .flat_map(|p| points_b.iter().map(move |q| p.distance(*q)))
                .fold(f64::INFINITY, f64::min);
            // No sampled pair is nearer than the distance, and the grid comes within its spacing.
            assert!(exact <= sampled + 1e-12, "{exact} > sampled {sampled}");
            assert!(sampled - exact <= 0.2, "{exact} far below sampled {sampled}");
        }
    }
}
