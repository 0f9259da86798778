//! `mem-sink`: moves pure ops and layout loads into the one conditional region that uses them
//! (level: any → same; paper §4.2.1, "derived fields are lazy").
//!
//! Destructor specialization reads a node's derived field where the traversal names it, all of
//! its parts at once: `left.bounds` of a DOP-14 node loads the hot axis slabs and the cold
//! diagonal slabs together, though the diagonal test that needs the cold ones runs only when
//! the axis test passes (layout catalog §5). Once `mem-inline` has put the test in the
//! traversal and `const-fold` has taken the record apart, the cold loads are used only inside
//! the `tree.if` of the diagonal test; this pass moves them there, so the second array is read
//! only by the nodes that get that far.
//!
//! An op moves when it is a pure `tree` op (not `tree.var`, `tree.load`, a call or an op with
//! regions) or `mem.buffer`, `mem.addr`, `mem.view` or `mem.load`, in a function that writes no
//! layout (`mem-cse`'s writers: no `mem.store`, no build op, no call of a writer), and every use
//! of its results lies inside one region of one later `tree.if` or `tree.match` of its block:
//! it then moves to the start of that region's block (never into a `tree.foreach`, which would
//! repeat it). The ops of a block are visited last to first, so a chain of loads and arithmetic
//! moves together; the walk repeats until nothing moves, so an op sinks as deep as its uses
//! allow. Moving never makes an op run more often, and what it reads cannot change in between.

use rustc_hash::{FxHashMap, FxHashSet};
use scion_ir::builder::{Builder, InsertPoint};
use scion_ir::module::{Module, RegionParent};
use scion_ir::op::OpKind;
use scion_ir::pass::{Pass, PassCx, PassError};
use scion_ir::{mem, tree, walk, BlockId, FuncId, OpId, RegionId};

/// The `mem-sink` pass.
#[derive(Default)]
pub struct MemSink;

impl Pass for MemSink {
    fn name(&self) -> &'static str {
        "mem-sink"
    }

    fn summary(&self) -> &'static str {
        "move pure ops and layout loads into the one conditional region that uses them"
    }

    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        let writers = super::cse::layout_writers(m);
        let mut changed = false;
        for f in m.func_order.clone() {
            if m.is_declaration(f) || writers.contains(&f) {
                continue;
            }
            if m.regions[m.funcs[f].body].blocks.len() != 1 {
                continue;
            }
            while sink_func(m, f) {
                changed = true;
            }
        }
        Ok(changed)
    }
}

fn movable(m: &Module, op: OpId) -> bool {
    let o = &m.ops[op];
    if !o.regions.is_empty() || o.results.is_empty() {
        return false;
    }
    match o.kind {
        OpKind::Mem(k) => matches!(
            k,
            mem::Op::Buffer | mem::Op::Addr | mem::Op::View | mem::Op::Load
        ),
        OpKind::Tree(k) => {
            k.is_pure()
                && !matches!(
                    k,
                    tree::Op::Var | tree::Op::Load | tree::Op::Call | tree::Op::Yield
                )
        }
        OpKind::Lo(_) => false,
    }
}

/// One pass over `f`'s blocks; whether anything moved.
fn sink_func(m: &mut Module, f: FuncId) -> bool {
    // Who uses each value.
    let mut users: FxHashMap<scion_ir::ValueId, Vec<OpId>> = FxHashMap::default();
    let mut blocks: Vec<BlockId> = Vec::new();
    walk::walk_region(m, m.funcs[f].body, walk::Order::Pre, &mut |op| {
        for &v in &m.ops[op].operands {
            users.entry(v).or_default().push(op);
        }
    });
    collect_blocks(m, m.funcs[f].body, &mut blocks);
    let mut moved = false;
    for &b in &blocks {
        let ops = m.blocks[b].ops.clone();
        for op in ops {
            moved |= lazy_element(m, op, &users);
        }
    }
    for b in blocks {
        let ops = m.blocks[b].ops.clone();
        for &op in ops.iter().rev() {
            if m.ops[op].parent != Some(b) || !movable(m, op) {
                continue;
            }
            let uses: Vec<OpId> = m.ops[op]
                .results
                .iter()
                .flat_map(|r| users.get(r).map(Vec::as_slice).unwrap_or(&[]))
                .copied()
                .collect();
            let Some(dest) = conditional_region(m, &uses, b) else {
                continue;
            };
            m.blocks[b].ops.retain(|&o| o != op);
            m.blocks[dest].ops.insert(0, op);
            m.ops[op].parent = Some(dest);
            moved = true;
        }
    }
    moved
}

/// A `tree.foreach` over a view whose element is used only inside one region of one
/// `tree.if` or `tree.match` of the loop's body: the element is read there, by a `tree.index`
/// of the view at the iteration's index, instead of at the top of every iteration (`mem-to-lo`
/// then loads no element for the loop). A leaf's `foreach tri, k in data { if (k & 3) == 0
/// {...} }` reads a triangle only on every fourth iteration. Needs the loop's index argument.
fn lazy_element(m: &mut Module, op: OpId, users: &FxHashMap<scion_ir::ValueId, Vec<OpId>>) -> bool {
    let o = &m.ops[op];
    if o.kind != OpKind::Tree(tree::Op::Foreach) || o.operands.len() != 1 || o.regions.len() != 1 {
        return false;
    }
    let view = o.operands[0];
    if !matches!(
        m.types.get(m.values[view].ty),
        scion_ir::types::Type::View(_)
    ) {
        return false;
    }
    let Some(&body) = m.regions[o.regions[0]].blocks.first() else {
        return false;
    };
    let [elem, index] = m.blocks[body].args[..] else {
        return false;
    };
    let Some(uses) = users.get(&elem) else {
        return false;
    };
    let Some(dest) = conditional_region(m, uses, body) else {
        return false;
    };
    let ty = m.values[elem].ty;
    let mut bd = Builder::new(m);
    bd.set_span(bd.m.span(op));
    bd.set_insertion_point(match bd.m.blocks[dest].ops.first() {
        Some(&first) => InsertPoint::Before(first),
        None => InsertPoint::End(dest),
    });
    let read = bd.build1(tree::Op::Index, &[view, index], ty);
    for &u in uses {
        for x in m.ops[u].operands.iter_mut() {
            if *x == elem {
                *x = read;
            }
        }
    }
    true
}

/// The first block of the one region of one `tree.if` or `tree.match` of block `b` that holds
/// every op of `uses` (at any depth), if there is such a region and `uses` is not empty.
fn conditional_region(m: &Module, uses: &[OpId], b: BlockId) -> Option<BlockId> {
    let mut target: Option<(OpId, RegionId)> = None;
    for &u in uses {
        match anchor(m, u, b) {
            Some((a, Some(region))) if target.is_none_or(|t| t == (a, region)) => {
                target = Some((a, region));
            }
            _ => return None,
        }
    }
    let (a, region) = target?;
    if !matches!(m.ops[a].kind, OpKind::Tree(tree::Op::If | tree::Op::Match)) {
        return None;
    }
    m.regions[region].blocks.first().copied()
}

fn collect_blocks(m: &Module, r: RegionId, out: &mut Vec<BlockId>) {
    for &b in &m.regions[r].blocks {
        out.push(b);
        for &op in &m.blocks[b].ops {
            for &inner in &m.ops[op].regions {
                collect_blocks(m, inner, out);
            }
        }
    }
}

/// The op of block `b` that (transitively) holds `user`, and the region of it the use is in
/// (`None` when `user` is itself in `b`). `None` when `user` is not inside `b`.
fn anchor(m: &Module, user: OpId, b: BlockId) -> Option<(OpId, Option<RegionId>)> {
    let mut op = user;
    let mut via: Option<RegionId> = None;
    let mut seen = FxHashSet::default();
    loop {
        if !seen.insert(op) {
            return None;
        }
        let block = m.ops[op].parent?;
        if block == b {
            return Some((op, via));
        }
        let region = m.blocks[block].parent?;
        match m.regions[region].parent? {
            RegionParent::Op(o) => {
                via = Some(region);
                op = o;
            }
            RegionParent::Func(_) => return None,
        }
    }
}
