//! What a layout's hits are compared with: the reference traversal of the tree its code
//! traverses ([`Traversed`]: the logical tree, read through the boxes the layout stores and
//! collapsed to the layout's children per node), and the one rule every check of hits follows
//! (`scion trace`, `scion run`, `scion render`, `scion explore`, the query-kind tests):
//!
//! * an answer equal to the reference's, bit for bit, is right;
//! * an answer that differs is right only when it is brute force's over the triangles and the
//!   reference's is not: the reference's own rounding exception (docs/runtime.md: a box on the
//!   way to brute force's hit fails the slab test or is entered beyond it by one rounding; a
//!   traversal over other boxes, of another width or of oriented nodes, need not share it);
//! * anything else is a wrong answer, named with both answers.
//!
//! Binary layouts are compared with the binary reference (`closest_hits_tree`), layouts whose
//! nodes hold arrays of 4 or 8 children with the wide reference over the tree collapsed to that
//! width (`closest_hit_wide`; node-quantized boxes decoded per node): the wide traversal visits
//! other boxes than the binary one, so on rays grazing axis-aligned geometry the two can differ
//! without either being wrong.

use crate::library::Resolved;
use crate::quantized::{decoded_wide, Boxes, DecodedTree};
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::bvh::LogicalTree;
use scion_runtime::geom::{Hit, Ray, Triangle};
use scion_runtime::reference::{closest_hit_brute, closest_hit_wide, closest_hits_tree};

/// The tree a layout's traversal reads.
#[derive(Clone, Copy, Debug)]
pub struct Traversed<'t> {
    /// The logical tree packed into the layout.
    pub tree: &'t LogicalTree,
    /// How the layout stores boxes (the traversal reads them decoded).
    pub boxes: Boxes,
    /// Children per interior node (2, 4 or 8).
    pub arity: u32,
}

impl<'t> Traversed<'t> {
    /// The tree `resolved`'s layout traverses when `tree` is packed into it.
    pub fn of(resolved: &Resolved, tree: &'t LogicalTree) -> Traversed<'t> {
        Traversed {
            tree,
            boxes: resolved.boxes,
            arity: resolved.arity,
        }
    }

    /// `tree` itself, binary, exact boxes (the layout-free reference's view).
    pub fn binary(tree: &'t LogicalTree) -> Traversed<'t> {
        Traversed {
            tree,
            boxes: Boxes::Exact,
            arity: 2,
        }
    }

    /// The reference traversal's name in messages.
    pub fn name(&self) -> &'static str {
        match self.arity {
            8 => "eight-wide reference",
            4 => "four-wide reference",
            _ => "reference",
        }
    }

    /// The reference traversal's closest hit of every ray; `Err` for a width it has no
    /// reference for.
    pub fn hits(&self, rays: &[Ray], driver: &BatchDriver) -> Result<Vec<Hit>, String> {
        fn wide<const W: usize>(boxes: Boxes, tree: &LogicalTree, rays: &[Ray]) -> Vec<Hit> {
            let exact = collapse::<W>(tree);
            let decoded = decoded_wide(boxes, &exact);
            rays.iter()
                .map(|r| closest_hit_wide(&decoded, &tree.primitives, r))
                .collect()
        }
        match self.arity {
            2 => Ok(closest_hits_tree(
                &self.boxes.decoded_tree(self.tree),
                rays,
                driver,
            )),
            4 => Ok(wide::<4>(self.boxes, self.tree, rays)),
            8 => Ok(wide::<8>(self.boxes, self.tree, rays)),
            n => Err(format!(
                "no reference traversal for trees of {n} children per node (2, 4 or 8)"
            )),
        }
    }
}

/// The outcome of a check that passed: how many answers there were and how many of them are
/// brute force's where the reference's rounding pruned it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Agreement {
    /// Answers checked.
    pub total: usize,
    /// Of those, answers that differ from the reference's and are brute force's.
    pub exceptions: usize,
}

impl Agreement {
    /// The verdict, e.g. "identical to the reference on all 1000 rays".
    pub fn describe(&self, reference: &str, what: &str) -> String {
        let n = self.total;
        match self.exceptions {
            0 => format!("identical to the {reference} on all {n} {what}"),
            k => format!(
                "identical to the {reference} on {} of {n} {what}; the other {k} are brute \
                 force's hits, which the reference's rounding pruned (docs/runtime.md)",
                n - k
            ),
        }
    }
}

/// Applies the rule of the module documentation to `n` answers: `differs(i)` says whether
/// answer `i` differs from the reference's, `is_brute(i, brute)` whether it is `brute` (brute
/// force's closest hit of ray `i`) and the reference's is not; `describe(i)` names both answers
/// for the error.
pub fn check_answers(
    rays: &[Ray],
    triangles: &[Triangle],
    differs: impl Fn(usize) -> bool,
    is_brute: impl Fn(usize, &Hit) -> bool,
    describe: impl Fn(usize) -> String,
) -> Result<Agreement, String> {
    let mut exceptions = 0;
    for (i, ray) in rays.iter().enumerate() {
        if !differs(i) {
            continue;
        }
        let brute = closest_hit_brute(triangles, ray);
        if !is_brute(i, &brute) {
            return Err(format!("{}; brute force's hit is {brute:?}", describe(i)));
        }
        exceptions += 1;
    }
    Ok(Agreement {
        total: rays.len(),
        exceptions,
    })
}

/// [`check_answers`] for closest hits `got` against the reference's `want`.
pub fn check_hits(
    got: &[Hit],
    want: &[Hit],
    rays: &[Ray],
    triangles: &[Triangle],
    reference: &str,
    what: &str,
) -> Result<Agreement, String> {
    assert_eq!(got.len(), rays.len(), "one hit per ray");
    assert_eq!(want.len(), rays.len(), "one reference hit per ray");
    let differ_count = || got.iter().zip(want).filter(|(g, w)| !g.bit_eq(w)).count();
    check_answers(
        rays,
        triangles,
        |i| !got[i].bit_eq(&want[i]),
        |i, brute| got[i].bit_eq(brute) && !want[i].bit_eq(brute),
        |i| {
            format!(
                "{what} {i}: the hit differs from the {reference}'s: got {:?}, reference {:?} \
                 ({} of {} {what}s differ)",
                got[i],
                want[i],
                differ_count(),
                rays.len()
            )
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use scion_runtime::bvh::{build_sah_binned, SahOptions};
    use scion_runtime::query::rays::secondary_rays;
    use scion_runtime::scene::gen;

    #[test]
    fn a_differing_hit_passes_only_as_brute_forces_where_the_reference_missed_it() {
        let scene = gen::random_soup(200, 1.0, 3);
        let rays = secondary_rays(scene.bounds(), 400, 5);
        let brute: Vec<Hit> = rays
            .iter()
            .map(|r| closest_hit_brute(&scene.triangles, r))
            .collect();
        let k = brute
            .iter()
            .position(|h| h.is_hit())
            .expect("a ray that hits");
        let check = |got: &[Hit], want: &[Hit]| {
            check_hits(got, want, &rays, &scene.triangles, "reference", "ray")
        };
        // The same answers: no exception.
        let a = check(&brute, &brute).unwrap();
        assert_eq!((a.total, a.exceptions), (400, 0));
        assert_eq!(
            a.describe("reference", "rays"),
            "identical to the reference on all 400 rays"
        );
        // The reference lost ray k's hit (as its rounding exception would): brute force's hit
        // passes, and is counted.
        let mut lost = brute.clone();
        lost[k] = Hit::MISS;
        let a = check(&brute, &lost).unwrap();
        assert_eq!(a.exceptions, 1);
        assert!(a
            .describe("reference", "rays")
            .contains("the other 1 are brute force's"));
        // Code that loses the hit the reference found, or finds another, is wrong.
        let e = check(&lost, &brute).unwrap_err();
        assert!(
            e.starts_with(&format!("ray {k}: the hit differs from the reference's")),
            "{e}"
        );
        let mut other = brute.clone();
        other[k].prim ^= 1;
        assert!(check(&other, &lost).is_err());
    }

    #[test]
    fn the_reference_follows_the_layouts_children_per_node() {
        let scene = gen::random_soup(300, 1.0, 9);
        let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
        let rays = secondary_rays(scene.bounds(), 300, 2);
        let driver = BatchDriver::new(1).unwrap();
        let mut t = Traversed::binary(&tree);
        assert_eq!(
            t.hits(&rays, &driver).unwrap(),
            closest_hits_tree(&tree, &rays, &driver)
        );
        assert_eq!(t.name(), "reference");
        t.arity = 8;
        let w8 = collapse::<8>(&tree);
        let wide: Vec<Hit> = rays
            .iter()
            .map(|r| closest_hit_wide(&w8, &tree.primitives, r))
            .collect();
        assert_eq!(t.hits(&rays, &driver).unwrap(), wide);
        assert_eq!(t.name(), "eight-wide reference");
        t.arity = 3;
        assert!(t.hits(&rays, &driver).unwrap_err().contains("3 children"));
    }
}
