//! Layout-free reference results (architecture §6): what every unquantized layout must return
//! bit for bit. [`prelude`] is the Rust image of `library/prelude.scion`'s arithmetic;
//! [`closest_hit`] is closest-hit ray tracing (paper Figure 4) by brute force and by logical
//! tree traversal; [`closest_hit_wide`] traverses a wide tree the same way; [`closest_point`]
//! answers closest point queries by brute force, in the prelude's `f32` arithmetic and in `f64`;
//! [`collide`] finds the colliding triangle pairs of two sets, tree-free; [`any_hit`] is the
//! float64 oracle of shadow rays; [`v64`] the `f64` vector arithmetic of the float64 oracles.

pub mod any_hit;
pub mod closest_hit;
pub mod closest_hit_wide;
pub mod closest_point;
pub mod collide;
pub mod prelude;
pub mod v64;

pub use closest_hit::{
    closest_hit_brute, closest_hit_dop14_stats, closest_hit_tree, closest_hit_tree_stats,
    closest_hit_with, closest_hits_brute, closest_hits_tree, closest_hits_tree_stats, why_pruned,
    why_pruned_in, why_pruned_with, TraversalStats,
};
pub use closest_hit_wide::{closest_hit_wide, closest_hit_wide_stats, closest_hits_wide_stats};
