use glam::Vec3;

/// A point where a leaf (or another organ) hangs on the skeleton.
#[derive(Clone, Copy, Debug, PartialEq)]
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
#[derive(Clone, Debug, Default, PartialEq)]
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
    }
}
