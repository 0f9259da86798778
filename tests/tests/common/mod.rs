//! A layout written by hand in Rust against the runtime contract ([`LayoutCode`]), standing in
//! for generated code until the JIT lands: it exercises the host (sizes, aligned buffers,
//! build, batches of 64, statuses) and shows what a layout row of the differential table is.
//!
//! `flat32`: buffer `nodes` (align 16), 32 bytes per node in depth-first pre-order from the
//! root: six `f32` bounds, then `a`, `b`: an interior node has `a` = left, `b` = right; a leaf
//! has `a` = first triangle, `b` = `0x8000_0000 | count`. Buffer `tris` (align 4), 40 bytes per
//! triangle: nine `f32` corners and the `u32` id. Traversal: the library's closest hit with the
//! prelude's arithmetic (nearer child first), an explicit stack of [`STACK`] entries; overflow
//! is status 1 (trees deeper than [`STACK`] + 1 nodes may overflow, shallower ones never do).

#![allow(dead_code)]

use scion_host::contract::{
    Best, BufferSpec, LayoutCode, LogicalInput, STATUS_OK, STATUS_STACK_OVERFLOW,
};
use scion_runtime::bvh::NO_NODE;
use scion_runtime::geom::{Aabb, Ray, Triangle, Vec3};
use scion_runtime::reference::prelude::{distmin_of, hit_distance, slab_ray};

/// Entries of the traversal stack.
pub const STACK: usize = 64;

/// See the module documentation.
pub struct Flat32;

fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}

fn vec_at(b: &[u8], at: usize) -> Vec3 {
    Vec3::new(f32_at(b, at), f32_at(b, at + 4), f32_at(b, at + 8))
}

impl LayoutCode for Flat32 {
    fn layout(&self) -> String {
        "flat32".into()
    }

    fn buffers(&self) -> Vec<BufferSpec> {
        vec![
            BufferSpec {
                name: "nodes".into(),
                align: 16,
            },
            BufferSpec {
                name: "tris".into(),
                align: 4,
            },
        ]
    }

    fn sizes(&self, input: &LogicalInput<'_>, sizes: &mut [u64]) {
        let tree = input.tree;
        sizes[0] = 32 * tree.nodes.len() as u64;
        sizes[1] = 40 * tree.primitives.len() as u64;
    }

    fn build(&self, input: &LogicalInput<'_>, buffers: &mut [&mut [u8]]) -> i32 {
        let tree = input.tree;
        if tree.nodes.len() >= 1 << 31 {
            return 2;
        }
        // Pre-order numbering from the root.
        let mut order = Vec::with_capacity(tree.nodes.len());
        let mut stack = vec![tree.root];
        while let Some(i) = stack.pop() {
            order.push(i);
            let n = &tree.nodes[i as usize];
            if !n.is_leaf() {
                stack.push(n.child[1]);
                stack.push(n.child[0]);
            }
        }
        let mut new_index = vec![NO_NODE; tree.nodes.len()];
        for (k, &i) in order.iter().enumerate() {
            new_index[i as usize] = k as u32;
        }
        let (nodes, rest) = buffers.split_at_mut(1);
        for (k, &i) in order.iter().enumerate() {
            let n = &tree.nodes[i as usize];
            let out = &mut nodes[0][32 * k..32 * k + 32];
            for (j, v) in n.bounds.iter().enumerate() {
                out[4 * j..4 * j + 4].copy_from_slice(&v.to_le_bytes());
            }
            let (a, b) = if n.is_leaf() {
                (n.prim_offset, 0x8000_0000 | n.prim_count)
            } else {
                (
                    new_index[n.child[0] as usize],
                    new_index[n.child[1] as usize],
                )
            };
            out[24..28].copy_from_slice(&a.to_le_bytes());
            out[28..32].copy_from_slice(&b.to_le_bytes());
        }
        for (k, t) in tree.primitives.iter().enumerate() {
            let out = &mut rest[0][40 * k..40 * k + 40];
            let corners = [t.p0, t.p1, t.p2];
            for (j, p) in corners.iter().enumerate() {
                for (l, v) in p.to_array().iter().enumerate() {
                    let at = 12 * j + 4 * l;
                    out[at..at + 4].copy_from_slice(&v.to_le_bytes());
                }
            }
            out[36..40].copy_from_slice(&t.id.to_le_bytes());
        }
        STATUS_OK
    }

    fn batch(&self, buffers: &[&[u8]], queries: &[Ray], results: &mut [Best]) -> i32 {
        let (nodes, tris) = (buffers[0], buffers[1]);
        let bounds = |i: u32| {
            let at = 32 * i as usize;
            Aabb::new(vec_at(nodes, at), vec_at(nodes, at + 12))
        };
        for (ray, result) in queries.iter().zip(results.iter_mut()) {
            let mut best = *result;
            let r = slab_ray(ray);
            // The library's algorithm: the root's box, then at each interior node both
            // children's boxes, the nearer child visited first (the left one on ties), the
            // farther one pushed with its entry distance and skipped if `best` has passed it.
            let mut stack = [(0u32, 0f32); STACK];
            let mut top = 0;
            let mut next = Some((0u32, distmin_of(&r, &bounds(0), best.t)))
                .filter(|&(_, d)| d < f32::INFINITY);
            while let Some((i, d)) = next.take().or_else(|| {
                (top > 0).then(|| {
                    top -= 1;
                    stack[top]
                })
            }) {
                // Skipped when `best` has passed it (or is NaN, as in generated code).
                let visit = d <= best.t;
                if !visit {
                    continue;
                }
                let at = 32 * i as usize;
                let (a, b) = (u32_at(nodes, at + 24), u32_at(nodes, at + 28));
                if b & 0x8000_0000 != 0 {
                    for k in a..a + (b & 0x7FFF_FFFF) {
                        let p = 40 * k as usize;
                        let t = Triangle {
                            p0: vec_at(tris, p),
                            p1: vec_at(tris, p + 12),
                            p2: vec_at(tris, p + 24),
                            id: u32_at(tris, p + 36),
                        };
                        let d = hit_distance(ray, &t);
                        if d < f32::INFINITY && (d < best.t || (d == best.t && t.id < best.id)) {
                            best = Best { t: d, id: t.id };
                        }
                    }
                    continue;
                }
                let da = distmin_of(&r, &bounds(a), best.t);
                let db = distmin_of(&r, &bounds(b), best.t);
                next = match (da < f32::INFINITY, db < f32::INFINITY) {
                    (true, true) => {
                        let (near, far) = if db < da {
                            ((b, db), (a, da))
                        } else {
                            ((a, da), (b, db))
                        };
                        if top == STACK {
                            return STATUS_STACK_OVERFLOW;
                        }
                        stack[top] = far;
                        top += 1;
                        Some(near)
                    }
                    (true, false) => Some((a, da)),
                    (false, true) => Some((b, db)),
                    (false, false) => None,
                };
            }
            *result = best;
        }
        STATUS_OK
    }

    /// A node at depth `k` (root 1) runs with at most `k - 1` pending entries and pushes one,
    /// so trees of depth up to [`STACK`] + 1 fit.
    fn stack_limit(&self) -> Option<usize> {
        Some(STACK + 1)
    }
}
