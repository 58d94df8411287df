//! Merging coincident nodes of adjacent mesh blocks.

use nalgebra::Point2;
use std::collections::HashMap;

/// Collects nodes and returns the same index for points closer than `tolerance` (blocks that
/// share an edge compute its nodes from the same formula, so their copies agree to round-off).
pub struct NodeMerger {
    tolerance: f64,
    cells: HashMap<(i64, i64), Vec<usize>>,
    pub nodes: Vec<Point2<f64>>,
}

impl NodeMerger {
    pub fn new(tolerance: f64) -> Self {
        Self {
            tolerance,
            cells: HashMap::new(),
            nodes: Vec::new(),
        }
    }

    fn cell(&self, p: &Point2<f64>) -> (i64, i64) {
        let size = 4.0 * self.tolerance;
        ((p.x / size).floor() as i64, (p.y / size).floor() as i64)
    }

    /// The index of `p`: an existing node within the tolerance, or a new one.
    pub fn insert(&mut self, p: Point2<f64>) -> usize {
        let (cx, cy) = self.cell(&p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(ids) = self.cells.get(&(cx + dx, cy + dy)) {
                    for &id in ids {
                        if (self.nodes[id] - p).norm() <= self.tolerance {
                            return id;
                        }
                    }
                }
            }
        }
        let id = self.nodes.len();
        self.nodes.push(p);
        self.cells.entry((cx, cy)).or_default().push(id);
        id
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merges_within_tolerance_only() {
        let mut m = NodeMerger::new(1e-9);
        let a = m.insert(Point2::new(0.01, 0.02));
        let b = m.insert(Point2::new(0.01 + 5e-10, 0.02 - 5e-10));
        let c = m.insert(Point2::new(0.01 + 5e-9, 0.02));
        assert_eq!(a, b);
        assert_ne!(a, c);
        assert_eq!(m.nodes.len(), 2);
    }
}
