//! Helpers shared by the integration tests: where the real scenes are, and a scratch folder.

#![allow(dead_code)]

use std::path::PathBuf;

use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::reference::why_pruned;

/// The real scenes' folder (`scene::manifest::scenes_dir`: the repository's `scenes/`, or
/// `SCION_SCENES`). The repository carries them, so a missing folder fails the test.
pub fn scenes_dir() -> Option<PathBuf> {
    let dir = scion_runtime::scene::manifest::scenes_dir();
    assert!(
        dir.is_some(),
        "no real scenes found: the repository's scenes/ folder is missing, or SCION_SCENES \
         names a folder without NAME.obj or NAME.obj.gz files"
    );
    dir
}

/// True when this is an optimized build (the large-scene tests run only then).
pub fn release() -> bool {
    !cfg!(debug_assertions)
}

/// A fresh scratch folder for one test.
pub fn scratch(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("scion-runtime-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

/// Compares traversal results with brute force. Every difference must be the documented
/// rounding case (docs/runtime.md, "Brute force and traversal"): the brute-force hit is in a
/// node whose computed entry distance exceeds that hit's distance (or whose box test fails),
/// so pruning dropped it; the traversal's hit is then never better than brute force's.
/// Returns the number of such rays.
pub fn check_against_brute(
    what: &str,
    tree: &LogicalTree,
    rays: &[Ray],
    got: &[Hit],
    brute: &[Hit],
) -> usize {
    let mut explained = 0;
    for (i, (g, b)) in got.iter().zip(brute).enumerate() {
        if g.bit_eq(b) {
            continue;
        }
        let ray = &rays[i];
        assert!(
            b.is_hit() && (b.t < g.t || (b.t == g.t && b.prim < g.prim)),
            "{what} ray {i} {ray:?}: traversal {g:?} is better than brute force {b:?}"
        );
        match why_pruned(tree, ray, b.prim, b.t) {
            Some((node, enter, exit)) => {
                if explained < 3 {
                    println!(
                        "  {what} ray {i}: traversal {g:?}, brute force {b:?}: node {node} \
                         pruned by rounding (enter {enter:e}, exit {exit:e})"
                    );
                }
                explained += 1;
            }
            None => panic!(
                "{what} ray {i} {ray:?}: traversal {g:?} != brute force {b:?}, and no node on \
                 the path to primitive {} is pruned",
                b.prim
            ),
        }
    }
    if explained > 3 {
        println!("  {what}: {explained} rays in all pruned by rounding");
    }
    explained
}
