//! Connected-component labels of the traversable grid, one labelling per head-height
//! threshold, so an unreachable target fails in O(goal cells) instead of a full A*.

use crate::grid::PlanGrid;

/// Label of cells that cannot be occupied at the threshold.
pub const BLOCKED: u32 = u32::MAX;

/// Component labels for one head-height threshold.
#[derive(Debug, Clone)]
pub struct Components {
    /// The head-height threshold the labels were built for \[m\].
    pub min_head: f32,
    /// Label per cell, [`BLOCKED`] where the cell is not passable.
    pub label: Vec<u32>,
    /// Number of components.
    pub count: u32,
}

impl Components {
    /// Label the grid by flood fill over the same edges A* uses.
    pub fn build(g: &PlanGrid, min_head: f32) -> Self {
        let n = g.len();
        let mut label = vec![BLOCKED; n];
        let mut count = 0u32;
        let mut stack = Vec::new();
        for s in 0..n {
            if label[s] != BLOCKED || !g.passable(s, min_head) {
                continue;
            }
            label[s] = count;
            stack.push(s);
            while let Some(c) = stack.pop() {
                for d in 0..8 {
                    if let Some((b, _)) = g.edge_for(c, d, min_head)
                        && label[b] == BLOCKED
                    {
                        label[b] = count;
                        stack.push(b);
                    }
                }
            }
            count += 1;
        }
        Self {
            min_head,
            label,
            count,
        }
    }

    /// Whether some goal cell shares the start's component.
    pub fn connected(&self, start: usize, goals: &[usize]) -> bool {
        let l = self.label[start];
        l != BLOCKED && goals.iter().any(|&c| self.label[c] == l)
    }
}
