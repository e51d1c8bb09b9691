//! From the directed contact graph to a tree: Edmonds' maximum arborescence (generic) and the
//! per-object part tree.

mod arborescence;
mod part_tree;

pub use arborescence::{WeightedEdge, max_arborescence};
pub use part_tree::{PartTree, TreeConfig, TreePart, build_part_tree, root_preference};
