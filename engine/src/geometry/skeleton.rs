use crate::math;
use glam::Vec3;

/// A point where a leaf (or another organ) hangs on the skeleton.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LeafPoint {
    /// The skeleton node the leaf hangs from.
    pub node: u32,
    /// Where the leaf's stalk starts.
    pub position: Vec3,
    /// The direction the leaf points (unit).
    pub direction: Vec3,
    /// A direction in the leaf's plane, across its axis (unit), for its orientation.
    pub side: Vec3,
    /// Leaf length.
    pub size: f32,
}

/// The branch graph shared by every tree algorithm.
///
/// Nodes are stored in topological order: a node's parent always has a smaller index, so a
/// forward pass visits parents before children and a backward pass children before parents
/// (the pipe model runs backwards). Several roots are allowed (a bush).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Skeleton {
    /// Node positions.
    pub positions: Vec<Vec3>,
    /// Parent of each node, `None` for a root.
    pub parents: Vec<Option<u32>>,
    /// Branch radius at each node.
    pub radii: Vec<f32>,
    /// Branch order: 0 for the trunk, +1 at each lateral branch.
    pub orders: Vec<u32>,
    /// Leaf attachment points recorded by the generator (turtle `~`, tips, ...).
    pub leaves: Vec<LeafPoint>,
}

impl Skeleton {
    /// An empty skeleton.
    #[must_use]
    pub fn new() -> Skeleton {
        Skeleton::default()
    }

    /// The bytes its buffers hold (what a script that keeps it is charged,
    /// [`crate::Budget`]).
    #[must_use]
    pub fn heap_bytes(&self) -> usize {
        use std::mem::size_of_val;
        size_of_val(self.positions.as_slice())
            + size_of_val(self.parents.as_slice())
            + size_of_val(self.radii.as_slice())
            + size_of_val(self.orders.as_slice())
            + size_of_val(self.leaves.as_slice())
    }

    /// Adds a node and returns its index.
    ///
    /// # Panics
    /// If `parent` is not an existing node (an invariant of the generator, not user input).
    pub fn push(&mut self, position: Vec3, parent: Option<u32>, radius: f32, order: u32) -> u32 {
        let index = self.positions.len() as u32;
        if let Some(p) = parent {
            assert!(p < index, "skeleton parent {p} must precede node {index}");
        }
        self.positions.push(position);
        self.parents.push(parent);
        self.radii.push(radius);
        self.orders.push(order);
        index
    }

    /// Number of nodes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are no nodes.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The children of every node, in index order.
    #[must_use]
    pub fn children(&self) -> Vec<Vec<u32>> {
        let mut children = vec![Vec::new(); self.len()];
        for (i, p) in self.parents.iter().enumerate() {
            if let Some(p) = p {
                children[*p as usize].push(i as u32);
            }
        }
        children
    }

    /// Indices of the nodes without children (branch tips).
    #[must_use]
    pub fn tips(&self) -> Vec<u32> {
        let mut has_child = vec![false; self.len()];
        for p in self.parents.iter().flatten() {
            has_child[*p as usize] = true;
        }
        (0..self.len() as u32)
            .filter(|i| !has_child[*i as usize])
            .collect()
    }

    /// Distance from each node to its root along the branches (0 at a root).
    #[must_use]
    pub fn path_lengths(&self) -> Vec<f32> {
        let mut d = vec![0.0; self.len()];
        for i in 0..self.len() {
            if let Some(p) = self.parents[i] {
                d[i] = d[p as usize] + self.positions[i].distance(self.positions[p as usize]);
            }
        }
        d
    }

    /// Appends every node and leaf point of `other` (its roots stay roots), moved by
    /// `transform`; returns the index of its first node here.
    pub fn append(&mut self, other: &Skeleton, transform: &glam::Mat4) -> u32 {
        let offset = self.len() as u32;
        let scale = transform.to_scale_rotation_translation().0;
        let radius_scale = math::cbrt(scale.x.abs() * scale.y.abs() * scale.z.abs());
        for i in 0..other.len() {
            self.positions
                .push(transform.transform_point3(other.positions[i]));
            self.parents.push(other.parents[i].map(|p| p + offset));
            self.radii.push(other.radii[i] * radius_scale);
            self.orders.push(other.orders[i]);
        }
        for leaf in &other.leaves {
            self.leaves.push(LeafPoint {
                node: leaf.node + offset,
                position: transform.transform_point3(leaf.position),
                direction: transform
                    .transform_vector3(leaf.direction)
                    .normalize_or_zero(),
                side: transform.transform_vector3(leaf.side).normalize_or_zero(),
                size: leaf.size * radius_scale,
            });
        }
        offset
    }

    /// The number of forks (nodes with two children or more) on the path from each node's
    /// root to the node, the node itself excluded: 0 along the trunk below its first fork.
    #[must_use]
    pub fn fork_depths(&self) -> Vec<u32> {
        let mut count = vec![0u32; self.len()];
        for p in self.parents.iter().flatten() {
            count[*p as usize] += 1;
        }
        let mut depth = vec![0u32; self.len()];
        for i in 0..self.len() {
            if let Some(p) = self.parents[i] {
                let p = p as usize;
                depth[i] = depth[p] + u32::from(count[p] >= 2);
            }
        }
        depth
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn children_tips_and_lengths() {
        let mut s = Skeleton::new();
        let root = s.push(Vec3::ZERO, None, 1.0, 0);
        let a = s.push(Vec3::Y, Some(root), 0.5, 0);
        let b = s.push(Vec3::new(1.0, 1.0, 0.0), Some(a), 0.2, 1);
        let c = s.push(Vec3::new(0.0, 3.0, 0.0), Some(a), 0.2, 0);
        assert_eq!(s.children()[a as usize], vec![b, c]);
        assert_eq!(s.tips(), vec![b, c]);
        assert_eq!(s.path_lengths(), vec![0.0, 1.0, 2.0, 3.0]);
        assert_eq!(s.fork_depths(), vec![0, 0, 1, 1]);
        let mut two = s.clone();
        let first = two.append(&s, &glam::Mat4::from_translation(Vec3::X));
        assert_eq!(first, 4);
        assert_eq!(two.parents[4], None);
        assert_eq!(two.parents[7], Some(5));
        assert_eq!(two.positions[7], Vec3::new(1.0, 3.0, 0.0));
        assert_eq!(two.radii[7], 0.2);
    }
}
