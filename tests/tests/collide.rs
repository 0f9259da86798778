//! Collision detection end to end: `library/algorithms/collide.scion` (two trees traversed
//! together, pairs through a sink; the explicit-stack `collide` and the `collide_recursive`
//! variant, calls on the machine stack) compiled for every library layout of the binary `BVH` by
//! both code generators, each scene against its copy rotated by (60°, 70°, 10°) (paper §9.3.3)
//! and against itself, over SAH and median-split trees: the pairs equal the tree-free reference
//! (`scion_runtime::reference::collide`, a sweep over the triangles' boxes with the prelude's
//! triangle test), and on the small scenes the brute force over all pairs.

use scion_host::collide::check_pairs;
use scion_host::entries::Entries;
use scion_host::jit::Codegen;
use scion_host::library::{library_entries, resolve_kind, QueryKind, LAYOUT_FILES};
use scion_runtime::geom::Triangle;
use scion_runtime::reference::collide::{collide_brute, collide_sweep, rotated};
use scion_runtime::scene::{gen, Scene};
use scion_tests::cases::{real_scene, TreeKind};

fn scenes() -> Vec<Scene> {
    let mut scenes: Vec<Scene> = gen::hard_cases()
        .into_iter()
        .filter(|s| !s.is_empty() && s.triangles.iter().all(Triangle::is_finite))
        .collect();
    scenes.push(real_scene("teapot").unwrap());
    scenes
}

#[test]
fn every_bvh_layout_and_backend_finds_the_reference_pairs() {
    let scenes = scenes();
    let mut rows = 0;
    let mut pairs_seen = 0;
    // Every collision entry the library declares over `BVH`.
    let entry_names: Vec<String> = library_entries()
        .unwrap()
        .into_iter()
        .filter(|(_, t, k)| *k == QueryKind::Collide && t == "BVH")
        .map(|(name, _, _)| name)
        .collect();
    assert!(
        entry_names.len() >= 2,
        "the stack and recursive variants: {entry_names:?}"
    );
    for &(stem, _) in LAYOUT_FILES {
        for entry in &entry_names {
            let Ok(resolved) = resolve_kind(stem, Some(entry), QueryKind::Collide) else {
                continue;
            };
            if resolved.tree_type != "BVH" {
                continue;
            }
            for codegen in [Codegen::Cranelift, Codegen::Llvm(3)] {
                let entries = Entries::compile(&resolved.program, codegen, Some(1024))
                    .unwrap_or_else(|e| panic!("{stem} {codegen:?}: {e}"));
                for scene in &scenes {
                    let copy = rotated(&scene.triangles, [60.0, 70.0, 10.0]);
                    let other = Scene::new(format!("{} rotated", scene.name), copy.clone());
                    for (b_scene, b_tris) in [(scene, &scene.triangles), (&other, &copy)] {
                        let want = collide_sweep(&scene.triangles, b_tris);
                        if scene.len() <= 2000 {
                            assert_eq!(
                                want,
                                collide_brute(&scene.triangles, b_tris),
                                "{}",
                                scene.name
                            );
                        }
                        for tree_kind in [TreeKind::Sah4, TreeKind::Median] {
                            let (ta, tb) = (tree_kind.build(scene), tree_kind.build(b_scene));
                            let pa = entries.pack(&ta).unwrap();
                            let pb = entries.pack(&tb).unwrap();
                            // A small first sink, so the rerun on a full sink runs too.
                            let got = entries
                                .collide(&pa, &pb, 3)
                                .unwrap_or_else(|e| panic!("{stem} {}: {e}", scene.name));
                            check_pairs(&got.pairs, &want).unwrap_or_else(|e| {
                                panic!(
                                    "{stem} {entry} {codegen:?} {} vs {} ({tree_kind:?}): {e}",
                                    scene.name, b_scene.name
                                )
                            });
                            assert_eq!(got.inserted, got.pairs.len() as u64, "a pair met twice");
                            pairs_seen += want.len();
                            rows += 1;
                        }
                    }
                }
            }
        }
    }
    eprintln!("{rows} rows, {pairs_seen} pairs");
    assert!(rows >= 2 * 9 * 2 * 2 * 2 * 5, "{rows} rows");
    assert!(pairs_seen > 0);
}
