//! The hand-written peer over the same bytes: closest hit written by hand in Rust for the
//! buffers the `pbrt` layout's generated builder packs (paper Figure 5a: PBRT-v4's 32-byte
//! `LinearBVHNode`, the primitives as 40-byte `Triangle`s), the way PBRT-v4's C++ kernel reads
//! them. It is what the paper calls the hand-written kernel: the benchmark measures the cost of
//! Scion's abstraction (layout-independent source, generated code) on identical data.
//!
//! It runs the library's algorithm (`library/algorithms/closest_hit.scion`: both children's
//! boxes tested at the parent with the ray's reciprocal direction computed once, nearer child
//! first, pruning on `d > best`) with the prelude's arithmetic, so its hits equal the
//! reference's bit for bit. Where an expert would, it does better than a literal translation:
//! the tree is validated once when the kernel is made, so the traversal reads it without bounds
//! checks, and `min`/`max` are one compare-and-select each where an operand cannot be NaN (the
//! prelude's slab test is written so that none of its distances is NaN after the first two
//! steps; see `slab_axis`), exactly as the compiler does.
//!
//! Node (32 bytes, `align 32`): `low: f32x3, high: f32x3` (24 B), then `p_o` (leaf: first
//! primitive) or `c_o` (interior: offset of the right child; the left child is the next node),
//! a `u32` at 24, and `nprims: u16` at 28 (0 for an interior node).

// Reinterpreting the packed buffers as typed slices, and reading them without bounds checks
// after one validation pass, is what makes this the hand-written baseline (PBRT's C++ does
// both); the validation in `PbrtKernel::new` is what makes the unchecked reads sound.
#![allow(unsafe_code)]

use scion_runtime::batch::BatchDriver;
use scion_runtime::geom::{Aabb, Hit, Ray, Triangle};
use scion_runtime::reference::prelude::{hit_distance, slab_ray, SlabRay, FAR_WIDENING};

/// PBRT-v4's `LinearBVHNode` as the `pbrt` layout packs it.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    offset: u32,
    nprims: u16,
    _pad: u16,
}

const _: () = assert!(std::mem::size_of::<Node>() == 32);
const _: () = assert!(std::mem::size_of::<Triangle>() == 40);

/// Entries of the traversal stack, as the generated code's default (`--stack-size`).
pub const STACK_SIZE: usize = 64;

/// The kernel over one packed tree.
pub struct PbrtKernel<'a> {
    nodes: &'a [Node],
    prims: &'a [Triangle],
}

/// `x` reinterpreted as a slice of `T` (checked: alignment and a whole number of elements).
fn cast<'b, T>(x: &'b [u8], what: &str) -> Result<&'b [T], String> {
    let size = std::mem::size_of::<T>();
    if x.len() % size != 0 {
        return Err(format!(
            "{what}: {} bytes is not a whole number of {size}-byte elements",
            x.len()
        ));
    }
    if x.as_ptr().align_offset(std::mem::align_of::<T>()) != 0 {
        return Err(format!("{what}: misaligned"));
    }
    // SAFETY: the pointer is aligned for `T`, the length covers whole `T`s inside `x`, `T` is
    // `repr(C)` plain old data made of `f32`/`u32`/`u16` fields (every bit pattern is valid),
    // and the result borrows `x`.
    Ok(unsafe { std::slice::from_raw_parts(x.as_ptr().cast::<T>(), x.len() / size) })
}

impl<'a> PbrtKernel<'a> {
    /// The kernel over the `pbrt` layout's buffers `globals`, `primitives`, `nodes` (in the
    /// plan's order, as `scion_host::contract::Packed::buffers` gives them), with the root at
    /// node 0 (the build is pre-order). Every child and primitive range is checked here once.
    pub fn new(buffers: &[&'a [u8]]) -> Result<PbrtKernel<'a>, String> {
        let [_, prims, nodes] = buffers else {
            return Err(format!(
                "pbrt layout: 3 buffers expected, {} given",
                buffers.len()
            ));
        };
        let nodes: &[Node] = cast(nodes, "nodes")?;
        let prims: &[Triangle] = cast(prims, "primitives")?;
        for (i, n) in nodes.iter().enumerate() {
            let ok = if n.nprims > 0 {
                (n.offset as usize)
                    .checked_add(usize::from(n.nprims))
                    .is_some_and(|end| end <= prims.len())
            } else {
                let right = i.checked_add(n.offset as usize);
                n.offset > 1 && i + 1 < nodes.len() && right.is_some_and(|r| r < nodes.len())
            };
            if !ok {
                return Err(format!("node {i}: child or primitive range out of bounds"));
            }
        }
        Ok(PbrtKernel { nodes, prims })
    }

    /// Bytes of the nodes and primitives.
    pub fn bytes(&self) -> usize {
        std::mem::size_of_val(self.nodes) + std::mem::size_of_val(self.prims)
    }

    /// Closest hits of `rays` over `driver`'s threads; an error names the first ray whose
    /// traversal overflowed the stack.
    pub fn trace(&self, rays: &[Ray], driver: &BatchDriver) -> Result<Vec<Hit>, String> {
        let hits = driver.map(rays, |r| self.closest_hit(r));
        match hits.iter().position(Option::is_none) {
            Some(i) => Err(format!(
                "ray {i}: the traversal stack ({STACK_SIZE} entries) overflowed"
            )),
            None => Ok(hits.into_iter().map(|h| h.unwrap_or(Hit::MISS)).collect()),
        }
    }

    #[inline(always)]
    fn node(&self, i: u32) -> &Node {
        debug_assert!((i as usize) < self.nodes.len());
        // SAFETY: every index reached is the root (0, checked non-empty by the caller), or a
        // child `i + 1` / `i + c_o` of a node that `new` checked to be in bounds.
        unsafe { self.nodes.get_unchecked(i as usize) }
    }

    /// Closest hit of one ray; `None` when the stack overflowed.
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let mut best = (ray.tmax, u32::MAX);
        if self.nodes.is_empty() {
            return Some(Hit::MISS);
        }
        let r = slab_ray(ray);
        let mut stack = [(0u32, 0f32); STACK_SIZE];
        let mut sp = 0usize;
        let mut node = 0u32;
        let mut d = distmin(&r, &self.node(0).bounds, best.0);
        if d == f32::INFINITY {
            return Some(Hit::MISS);
        }
        loop {
            if d <= best.0 {
                let n = self.node(node);
                if n.nprims > 0 {
                    let start = n.offset as usize;
                    // SAFETY: `new` checked `p_o + nprims <= P` for every leaf.
                    let tris = unsafe {
                        self.prims
                            .get_unchecked(start..start + usize::from(n.nprims))
                    };
                    for tri in tris {
                        let h = hit_distance(ray, tri);
                        if h < best.0 || (h == best.0 && h < f32::INFINITY && tri.id < best.1) {
                            best = (h, tri.id);
                        }
                    }
                } else {
                    let (left, right) = (node + 1, node + n.offset);
                    let dl = distmin(&r, &self.node(left).bounds, best.0);
                    let dr = distmin(&r, &self.node(right).bounds, best.0);
                    let (hl, hr) = (dl < f32::INFINITY, dr < f32::INFINITY);
                    if hl && hr {
                        // Visit the nearer now, push the other (left first on ties).
                        let (near, dn, far, df) = if dr < dl {
                            (right, dr, left, dl)
                        } else {
                            (left, dl, right, dr)
                        };
                        if sp == STACK_SIZE {
                            return None;
                        }
                        stack[sp] = (far, df);
                        sp += 1;
                        node = near;
                        d = dn;
                        continue;
                    } else if hl {
                        node = left;
                        d = dl;
                        continue;
                    } else if hr {
                        node = right;
                        d = dr;
                        continue;
                    }
                }
            }
            if sp == 0 {
                break;
            }
            sp -= 1;
            (node, d) = stack[sp];
        }
        Some(Hit::from_best(best.0, best.1))
    }
}

/// `min` for operands of which the first is not NaN: the prelude's `min` (the first operand on
/// ties, the non-NaN one when the second is NaN) as one compare-and-select.
#[inline(always)]
fn min1(a: f32, b: f32) -> f32 {
    if b < a {
        b
    } else {
        a
    }
}

/// `max` likewise.
#[inline(always)]
fn max1(a: f32, b: f32) -> f32 {
    if b > a {
        b
    } else {
        a
    }
}

/// The prelude's `distmin(r, box, tmax)` (`scion_runtime::reference::prelude::distmin_of`),
/// bit for bit, with one-instruction `min`/`max`: `(lo - o) * inv` is NaN only for an axis
/// with `inv = +inf` and the origin on the plane, which `max(t0, -inf)` / `min(t1, inf)` map
/// to -inf / +inf as the prelude's `max`/`min` do (ties there are only with the infinity
/// itself, so the order of the operands does not matter).
#[inline(always)]
fn distmin(r: &SlabRay, b: &Aabb, tmax: f32) -> f32 {
    let o = r.origin;
    let axis = |lo: f32, hi: f32, o: f32, inv: f32| {
        let t0 = (lo - o) * inv;
        let t1 = (hi - o) * inv;
        let t0 = if t0 > f32::NEG_INFINITY {
            t0
        } else {
            f32::NEG_INFINITY
        };
        let t1 = if t1 < f32::INFINITY {
            t1
        } else {
            f32::INFINITY
        };
        (min1(t0, t1), max1(t0, t1))
    };
    let x = axis(b.low.x, b.high.x, o.x, r.inv.x);
    let y = axis(b.low.y, b.high.y, o.y, r.inv.y);
    let z = axis(b.low.z, b.high.z, o.z, r.inv.z);
    let enter = max1(max1(x.0, max1(y.0, z.0)), r.tmin);
    let exit = min1(min1(x.1, min1(y.1, z.1)) * FAR_WIDENING, tmax);
    if enter <= exit {
        enter
    } else {
        f32::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scion_host::contract::Packed;
    use scion_host::jit::JitClosestHit;
    use scion_runtime::bvh::{build_median, build_sah_binned, SahOptions};
    use scion_runtime::query::{axis_rays, secondary_rays};
    use scion_runtime::reference::closest_hits_tree;
    use scion_runtime::scene::gen;

    /// On every hard case (both builders; axis-parallel rays with signed-zero lanes and random
    /// ones), the kernel over the generated builder's bytes returns the reference's hits bit
    /// for bit, and reports a stack overflow exactly where the reference needs more entries.
    #[test]
    fn hand_written_kernel_matches_the_reference() {
        let code = JitClosestHit::compile("pbrt", "LinearBVH", None).unwrap();
        let driver = BatchDriver::new(2).unwrap();
        let mut compared = 0;
        for (i, s) in gen::hard_cases().iter().enumerate() {
            for tree in [
                build_sah_binned(&s.triangles, &SahOptions::default()),
                build_median(&s.triangles),
            ] {
                let mut rays = axis_rays(s.bounds(), 300, i as u64);
                rays.extend(secondary_rays(s.bounds(), 300, i as u64));
                let want = closest_hits_tree(&tree, &rays, &driver);
                if tree.is_empty() {
                    continue;
                }
                let packed = Packed::new(&code, &tree).unwrap();
                let buffers = packed.buffers();
                let kernel = PbrtKernel::new(&buffers).unwrap();
                match kernel.trace(&rays, &driver) {
                    Ok(got) => {
                        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                            assert!(g.bit_eq(w), "{}: ray {k}: {g:?} vs {w:?}", s.name);
                        }
                        compared += rays.len();
                    }
                    Err(e) => {
                        // Only a traversal needing more than STACK_SIZE entries may fail.
                        let mut stats = scion_runtime::reference::TraversalStats::default();
                        for r in &rays {
                            scion_runtime::reference::closest_hit_tree_stats(&tree, r, &mut stats);
                        }
                        assert!(stats.max_pending as usize > STACK_SIZE, "{}: {e}", s.name);
                    }
                }
            }
        }
        assert!(compared > 10_000, "{compared}");
    }

    #[test]
    fn malformed_buffers_are_refused() {
        let nodes = vec![0u8; 32];
        let prims = vec![0u8; 40];
        assert!(PbrtKernel::new(&[&[], &prims, &nodes[..31]]).is_err());
        // An interior node (nprims 0) whose right child is out of bounds.
        let e = PbrtKernel::new(&[&[], &prims, &nodes]).err().unwrap();
        assert!(e.contains("node 0"), "{e}");
        assert!(PbrtKernel::new(&[&prims]).is_err());
    }
}
