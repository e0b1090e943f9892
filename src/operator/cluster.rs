//! Cluster trees: items (collocation nodes, or elements) ordered so that every cluster is a
//! contiguous range, split by geometric bisection of bounding boxes.

use glam::DVec3;

/// One cluster: items `start..end` of the tree's order.
#[derive(Clone, Debug)]
pub struct Cluster {
    /// First item (position in the tree's order).
    pub start: usize,
    /// One past the last item.
    pub end: usize,
    /// Bounding box of the items' extents.
    pub lo: DVec3,
    /// Upper corner of the box.
    pub hi: DVec3,
    /// The two halves, or `None` for a leaf.
    pub children: Option<(usize, usize)>,
    /// Faces the items lie on, sorted.
    pub faces: Vec<usize>,
}

impl Cluster {
    /// Number of items.
    pub fn len(&self) -> usize {
        self.end - self.start
    }

    /// Whether it holds no item (only an empty scene gives one).
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }

    /// Diameter of its box.
    pub fn diameter(&self) -> f64 {
        (self.hi - self.lo).length()
    }

    /// Distance between its box and another's (0 when they overlap).
    pub fn distance(&self, other: &Cluster) -> f64 {
        let gap = (other.lo - self.hi).max(self.lo - other.hi).max(DVec3::ZERO);
        gap.length()
    }

    /// The box as a pair of corners.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        (self.lo, self.hi)
    }
}

/// A binary cluster tree; cluster 0 is the root.
#[derive(Clone, Debug)]
pub struct ClusterTree {
    /// `order[k]`: the original index of the item at position k.
    pub order: Vec<usize>,
    /// Clusters, parents before children.
    pub clusters: Vec<Cluster>,
}

/// One item to cluster: where it is (for splitting), how far it reaches (for the boxes), its face.
#[derive(Clone, Copy, Debug)]
pub struct Item {
    /// Reference point (node position, element centroid).
    pub point: DVec3,
    /// Lower corner of its extent.
    pub lo: DVec3,
    /// Upper corner of its extent.
    pub hi: DVec3,
    /// Face.
    pub face: usize,
}

impl ClusterTree {
    /// Splits `items` until clusters hold at most `leaf_size`. A cluster on several faces is cut
    /// between whole faces (by the faces' centres), so that below it every cluster lies on one
    /// face: the kernel is one smooth function on a pair of such clusters, while on several faces
    /// it is a patchwork (zero between coplanar parts) that cross approximation can miss. A
    /// cluster on one face is cut at the middle of the longest side of its points' box (at the
    /// median instead when that leaves one side empty, as for items at one point).
    pub fn new(items: &[Item], leaf_size: usize) -> Self {
        let mut tree = Self { order: (0..items.len()).collect(), clusters: Vec::new() };
        let faces = items.iter().map(|it| it.face + 1).max().unwrap_or(0);
        let (mut sum, mut count) = (vec![DVec3::ZERO; faces], vec![0.0; faces]);
        for it in items {
            sum[it.face] += it.point;
            count[it.face] += 1.0;
        }
        let centres: Vec<DVec3> =
            sum.iter().zip(&count).map(|(s, c)| *s / f64::max(*c, 1.0)).collect();
        tree.split(items, &centres, 0, items.len(), leaf_size.max(1));
        tree
    }

    /// Builds the cluster of `start..end` and, below it, its descendants; returns its index.
    fn split(
        &mut self,
        items: &[Item],
        centres: &[DVec3],
        start: usize,
        end: usize,
        leaf_size: usize,
    ) -> usize {
        let index = self.clusters.len();
        let members = &self.order[start..end];
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        let (mut plo, mut phi) = (lo, hi);
        let mut faces: Vec<usize> = Vec::new();
        for &k in members {
            let it = &items[k];
            lo = lo.min(it.lo);
            hi = hi.max(it.hi);
            plo = plo.min(it.point);
            phi = phi.max(it.point);
            faces.push(it.face);
        }
        faces.sort_unstable();
        faces.dedup();
        // The list held one entry per member: a tree of n items would keep n of them on each
        // of its levels (most clusters are on one face).
        faces.shrink_to_fit();
        let several_faces = faces.len() > 1;
        self.clusters.push(Cluster { start, end, lo, hi, children: None, faces });
        if end - start <= leaf_size && !several_faces {
            return index;
        }
        let slice = &mut self.order[start..end];
        let cut = if several_faces {
            split_faces(slice, items, centres)
        } else {
            split_points(slice, items, plo, phi)
        };
        let left = self.split(items, centres, start, start + cut, leaf_size);
        let right = self.split(items, centres, start + cut, end, leaf_size);
        self.clusters[index].children = Some((left, right));
        index
    }
}

/// Cuts items on several faces between faces: at the middle of the longest side of the box of
/// the faces' centres, or by face number where the centres coincide (two sides of a plate).
fn split_faces(slice: &mut [usize], items: &[Item], centres: &[DVec3]) -> usize {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for &k in slice.iter() {
        lo = lo.min(centres[items[k].face]);
        hi = hi.max(centres[items[k].face]);
    }
    let axis = longest_axis(hi - lo);
    if hi[axis] > lo[axis] {
        let middle = 0.5 * (lo[axis] + hi[axis]);
        let cut = partition(slice, |&k| centres[items[k].face][axis] < middle);
        if cut > 0 && cut < slice.len() {
            return cut;
        }
    }
    let (first, last) = slice
        .iter()
        .fold((usize::MAX, 0), |(a, b), &k| (a.min(items[k].face), b.max(items[k].face)));
    partition(slice, |&k| items[k].face < first + (last - first).div_ceil(2))
}

/// Cuts items on one face at the middle of the longest side of their points' box `[lo, hi]`.
fn split_points(slice: &mut [usize], items: &[Item], lo: DVec3, hi: DVec3) -> usize {
    let axis = longest_axis(hi - lo);
    let middle = 0.5 * (lo[axis] + hi[axis]);
    let mut cut = partition(slice, |&k| items[k].point[axis] < middle);
    if cut == 0 || cut == slice.len() {
        cut = slice.len() / 2;
        slice.select_nth_unstable_by(cut, |&a, &b| {
            items[a].point[axis].total_cmp(&items[b].point[axis])
        });
    }
    cut
}

/// 0, 1 or 2: the axis of the largest component.
fn longest_axis(extent: DVec3) -> usize {
    if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    }
}

/// Moves the items for which `left` holds to the front; returns how many there are.
fn partition(slice: &mut [usize], left: impl Fn(&usize) -> bool) -> usize {
    let mut cut = 0;
    for k in 0..slice.len() {
        if left(&slice[k]) {
            slice.swap(cut, k);
            cut += 1;
        }
    }
    cut
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(x: f64, y: f64, face: usize) -> Item {
        let p = DVec3::new(x, y, 0.0);
        Item { point: p, lo: p, hi: p, face }
    }

    #[test]
    fn clusters_are_contiguous_ranges_with_boxes_holding_their_items() {
        let items: Vec<Item> =
            (0..100).map(|k| point((k % 10) as f64, (k / 10) as f64, k / 50)).collect();
        let tree = ClusterTree::new(&items, 8);
        let mut sorted = tree.order.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..100).collect::<Vec<_>>());
        for c in &tree.clusters {
            for &k in &tree.order[c.start..c.end] {
                assert!(items[k].point.cmpge(c.lo).all() && items[k].point.cmple(c.hi).all());
                assert!(c.faces.contains(&items[k].face));
            }
            // A cluster keeps its faces, not a slot per member (n per level of the tree).
            assert_eq!(c.faces.capacity(), c.faces.len());
            match c.children {
                Some((l, r)) => {
                    assert_eq!(
                        (tree.clusters[l].start, tree.clusters[l].end),
                        (c.start, tree.clusters[r].start)
                    );
                    assert_eq!(tree.clusters[r].end, c.end);
                    assert!(c.len() > 8);
                }
                None => assert!(c.len() <= 8 && !c.is_empty()),
            }
        }
    }

    #[test]
    fn items_at_one_point_are_split_at_the_median() {
        let items: Vec<Item> = (0..20).map(|_| point(1.0, 1.0, 0)).collect();
        let tree = ClusterTree::new(&items, 4);
        assert!(tree.clusters.iter().all(|c| c.children.is_some() || c.len() <= 4));
    }
}
