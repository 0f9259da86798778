//! The exported `lo` entry functions of docs/design/backends.md §1, built with the IR builder
//! after the module is lowered to `lo`.
//!
//! Input: the `lo` module (with `@A`, `@L.sizes`, `@L.build`, `@L.node`) and the [`EntrySig`].
//! Output: the same module with `@scion_L_sizes`, `@scion_L_build`, `@scion_L_root`,
//! `@scion_A_L` and, for [`EntryTarget::Gpu`], `@scion_A_L_kernel`, `@scion_L_sizes_kernel`,
//! `@scion_L_build_kernel`, `@scion_L_root_kernel`; all carry the attribute `export`, the kernels
//! also `kernel`.
//!
//! The batch entry loads query `i`'s scalars from `queries + i * sizeof(query)`, passes
//! `results + i * sizeof(result) + offset` for each `mut` parameter, calls `@A` and stops at
//! the first nonzero status (when `@A` returns one: the attribute `status`).
//! `@scion_L_root` calls `@L.node` on the logical root (`tree + 12`) with fresh zeroed counter,
//! cursor and status cells, placing every node where `@L.build` did; for an empty tree
//! (`node_count == 0`) it returns 0 without reading any node.

use super::{EntrySig, EntryTarget, Role};
use crate::passes::tree_to_mem::constructor::view;
use scion_ir::attr::Attr;
use scion_ir::diag::Diagnostic;
use scion_ir::entity::{BlockId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::tree::CmpPred;
use scion_ir::types::{IntTy, Type};
use scion_ir::{Builder, FuncId, Module};

/// Types used by the entries.
struct Tys {
    ptr: TypeId,
    u32: TypeId,
    u64: TypeId,
    i32: TypeId,
    root: TypeId,
    /// `@L.root_ref` and its results (the scalar leaves of the whole reference), for a
    /// reference of several components.
    root_ref: Option<(String, Vec<TypeId>)>,
}

/// What the lowered algorithm looks like.
struct Algo {
    name: String,
    status: bool,
}

fn ice(msg: String) -> Diagnostic {
    Diagnostic::error("E0916", msg)
        .with_note("the algorithm and the layout's functions must all be lowered to lo")
}

/// Adds the entries of `sig` to the `lo` module `m`.
pub fn add(m: &mut Module, sig: &EntrySig, target: EntryTarget) -> Result<(), Diagnostic> {
    let l = &sig.layout;
    let node = format!("{l}.node");
    let need = [
        sig.algorithm.clone(),
        format!("{l}.sizes"),
        format!("{l}.build"),
        node.clone(),
    ];
    for n in &need {
        if m.func_by_name(n).is_none() {
            return Err(ice(format!(
                "`--entry {}`: `@{n}` was not lowered to lo",
                sig.algorithm
            )));
        }
    }
    let mut names = vec![
        sig.layout_fn("sizes"),
        sig.layout_fn("build"),
        sig.layout_fn("root"),
        sig.batch_fn(),
    ];
    if target == EntryTarget::Gpu {
        names.extend([
            format!("{}_kernel", sig.batch_fn()),
            format!("{}_kernel", sig.layout_fn("sizes")),
            format!("{}_kernel", sig.layout_fn("build")),
            format!("{}_kernel", sig.layout_fn("root")),
        ]);
    }
    if let Some(n) = names.iter().find(|n| m.func_by_name(n).is_some()) {
        return Err(Diagnostic::error(
            "E0916",
            format!("the entry `{n}` is already a function of the module"),
        )
        .with_note("rename the function of the inputs"));
    }
    let nf = m.func_by_name(&node).expect("checked above");
    let root = match m.funcs[nf].results.as_slice() {
        [r] if matches!(m.types.get(*r), Type::Int(_) | Type::Ptr) => *r,
        _ => {
            return Err(Diagnostic::error(
                "E0913",
                format!("the reference of layout `{l}` is not one integer or pointer"),
            )
            .with_note("entry points pass the root reference as one scalar"))
        }
    };
    // A reference of several components: the entries take its placed first component and
    // `@L.root_ref` gives the root's whole reference (its other components from their defaults).
    let root_ref = {
        let name = format!("{l}.root_ref");
        m.func_by_name(&name)
            .map(|f| (name, m.funcs[f].results.clone()))
    };
    let t = Tys {
        root_ref,
        ptr: m.ty(Type::Ptr),
        u32: m.types.u32(),
        u64: m.types.int(IntTy::U64),
        i32: m.types.i32(),
        root,
    };
    let algo = check_algorithm(m, sig, &t)?;

    sizes(m, sig, &t, false);
    build(m, sig, &t, false);
    root_fn(m, sig, &t, false);
    batch(m, sig, &t, &algo);
    if target == EntryTarget::Gpu {
        batch_kernel(m, sig, &t, &algo);
        sizes(m, sig, &t, true);
        build(m, sig, &t, true);
        root_fn(m, sig, &t, true);
    }
    Ok(())
}

/// Checks that the lowered `@A` takes what `sig` says, and whether it returns a status.
fn check_algorithm(m: &Module, sig: &EntrySig, t: &Tys) -> Result<Algo, Diagnostic> {
    let f = m
        .func_by_name(&sig.algorithm)
        .expect("checked by the caller");
    let mut want = vec![t.ptr; sig.trees()];
    for r in &sig.roles {
        match r {
            Role::Tree => match &t.root_ref {
                Some((_, leaves)) => want.extend(leaves.iter().copied()),
                None => want.push(t.root),
            },
            Role::Result(_) => want.push(t.ptr),
            Role::Query(fields) => {
                for fd in &sig.query.fields[fields.clone()] {
                    want.push(m.types.lookup(&fd.ty).unwrap_or(t.ptr));
                }
            }
        }
    }
    let func = &m.funcs[f];
    let status = func.attrs.get("status").is_some();
    let results_ok = if status {
        func.results == [t.i32]
    } else {
        func.results.is_empty()
    };
    if func.params != want || !results_ok {
        return Err(ice(format!(
            "`--entry {}`: the lowered `@{}` has an unexpected signature",
            sig.algorithm, sig.algorithm
        )));
    }
    Ok(Algo {
        name: sig.algorithm.clone(),
        status,
    })
}

fn new_func(
    m: &mut Module,
    name: String,
    params: &[TypeId],
    results: &[TypeId],
    kernel: bool,
) -> (FuncId, BlockId, Vec<ValueId>) {
    let (f, entry) = m.add_func(&name, params, results);
    m.funcs[f].attrs.set("export", Attr::Unit);
    if kernel {
        m.funcs[f].attrs.set("kernel", Attr::Unit);
    }
    let args = m.blocks[entry].args.to_vec();
    (f, entry, args)
}

fn int_list(ks: &[i128]) -> Attr {
    Attr::List(ks.iter().map(|&k| Attr::Int(k)).collect())
}

fn kname(base: String, kernel: bool) -> String {
    if kernel {
        format!("{base}_kernel")
    } else {
        base
    }
}

/// `@scion_L_sizes(%tree, %sizes)`.
fn sizes(m: &mut Module, sig: &EntrySig, t: &Tys, kernel: bool) {
    let name = kname(sig.layout_fn("sizes"), kernel);
    let (_, entry, a) = new_func(m, name, &[t.ptr, t.ptr], &[], kernel);
    let mut b = Builder::at_end(m, entry);
    b.lo_call(&format!("{}.sizes", sig.layout), &a, &[]);
    b.lo_ret(&[]);
}

/// `@scion_L_build(%tree, %B) -> (i32)`, or the kernel storing the status to `*%status`.
fn build(m: &mut Module, sig: &EntrySig, t: &Tys, kernel: bool) {
    let name = kname(sig.layout_fn("build"), kernel);
    let (params, results) = if kernel {
        (vec![t.ptr; 3], vec![])
    } else {
        (vec![t.ptr; 2], vec![t.i32])
    };
    let (_, entry, a) = new_func(m, name, &params, &results, kernel);
    let mut b = Builder::at_end(m, entry);
    let call = b.lo_call(&format!("{}.build", sig.layout), &a[..2], &[t.i32]);
    let s = b.result(call, 0);
    if kernel {
        b.lo_store(a[2], 0, s);
        b.lo_ret(&[]);
    } else {
        b.lo_ret(&[s]);
    }
}

/// `@scion_L_root(%tree, %B) -> (R)`, or the kernel storing it to `*%root`.
fn root_fn(m: &mut Module, sig: &EntrySig, t: &Tys, kernel: bool) {
    let name = kname(sig.layout_fn("root"), kernel);
    if kernel {
        let (_, entry, a) = new_func(m, name, &[t.ptr; 3], &[], true);
        let mut b = Builder::at_end(m, entry);
        let call = b.lo_call(&sig.layout_fn("root"), &a[..2], &[t.root]);
        let r = b.result(call, 0);
        b.lo_store(a[2], 0, r);
        b.lo_ret(&[]);
        return;
    }
    let (f, entry, a) = new_func(m, name, &[t.ptr; 2], &[t.root], false);
    let body = m.funcs[f].body;
    let place = m.add_block(body, &[]);
    let empty = m.add_block(body, &[]);
    let mut b = Builder::at_end(m, entry);
    let count = b.lo_load(a[0], view::NODE_COUNT as i64, t.u32);
    let zero = b.lo_int(t.u32, 0);
    let none = b.lo_cmp(CmpPred::Eq, count, zero);
    b.lo_cond_br(none, (empty, &[]), (place, &[]));
    b.set_insertion_point_to_end(empty);
    let null = b.lo_int(t.root, 0);
    b.lo_ret(&[null]);
    b.set_insertion_point_to_end(place);
    let i = b.lo_load(a[0], view::ROOT as i64, t.u32);
    // The placement counters (one `u32`, or one per indirect group), the cursor, the status.
    let counters =
        b.m.func_by_name(&format!("{}.node", sig.layout))
            .and_then(|f| {
                b.m.funcs[f]
                    .attrs
                    .get(crate::passes::tree_to_mem::counters::COUNTERS_ATTR)
            })
            .and_then(scion_ir::attr::Attr::as_int)
            .unwrap_or(1)
            .max(1) as usize;
    let cells: Vec<ValueId> = [counters, 1, 1]
        .into_iter()
        .map(|words| {
            let c = b.lo_stack_slot(4 * words as u64, 4);
            let z = b.lo_int(t.u32, 0);
            for k in 0..words {
                b.lo_store(c, 4 * k as i64, z);
            }
            c
        })
        .collect();
    let call = b.lo_call(
        &format!("{}.node", sig.layout),
        &[a[0], a[1], i, cells[0], cells[1], cells[2]],
        &[t.root],
    );
    let r = b.result(call, 0);
    b.lo_ret(&[r]);
}

/// Runs query `i` at the builder's insertion point: loads its scalars, points at its result
/// record and calls `@A`. Returns the status (`None` when `@A` has none).
#[allow(clippy::too_many_arguments)]
fn run_query(
    b: &mut Builder<'_>,
    sig: &EntrySig,
    t: &Tys,
    algo: &Algo,
    tables: &[ValueId],
    queries: ValueId,
    results: ValueId,
    i: ValueId,
    roots: &[Vec<ValueId>],
) -> Option<ValueId> {
    let q = if sig.query.size > 0 {
        let size = b.lo_int(t.u64, sig.query.size as i128);
        let off = b.lo1(L::Mul, &[i, size], t.u64);
        b.lo1(L::PtrAdd, &[queries, off], t.ptr)
    } else {
        queries
    };
    let r = if sig.result.size > 0 {
        let size = b.lo_int(t.u64, sig.result.size as i128);
        let off = b.lo1(L::Mul, &[i, size], t.u64);
        b.lo1(L::PtrAdd, &[results, off], t.ptr)
    } else {
        results
    };
    let mut args = tables.to_vec();
    let mut roots = roots.iter();
    for role in &sig.roles {
        match role {
            Role::Tree => args.extend(roots.next().into_iter().flatten().copied()),
            Role::Result(off) => args.push(if *off == 0 {
                r
            } else {
                let o = b.lo_int(t.u64, *off as i128);
                b.lo1(L::PtrAdd, &[r, o], t.ptr)
            }),
            Role::Query(fields) => {
                for fd in &sig.query.fields[fields.clone()] {
                    let ty = b.m.ty(fd.ty.clone());
                    let v = b.lo_load(q, fd.offset as i64, ty);
                    args.push(v);
                }
            }
        }
    }
    let res: &[TypeId] = if algo.status { &[t.i32] } else { &[] };
    let call = b.lo_call(&algo.name, &args, res);
    algo.status.then(|| b.result(call, 0))
}

/// The traversal's root reference from the entry's `root`: itself, or for a reference of
/// several components the leaves `@L.root_ref(%B, %root)` gives.
fn root_leaves(b: &mut Builder<'_>, t: &Tys, bufs: ValueId, root: ValueId) -> Vec<ValueId> {
    match &t.root_ref {
        None => vec![root],
        Some((name, leaves)) => {
            let call = b.lo_call(name, &[bufs, root], leaves);
            (0..leaves.len()).map(|k| b.result(call, k)).collect()
        }
    }
}

/// The parameters after the first tree's, for an entry over several trees: `(%B_k, %root_k)`
/// for each other tree, and their indices.
fn more_trees(sig: &EntrySig, t: &Tys, first: usize) -> (Vec<TypeId>, Vec<(usize, usize)>) {
    let mut params = Vec::new();
    let mut at = Vec::new();
    for k in 1..sig.trees() {
        let i = first + 2 * (k - 1);
        params.extend([t.ptr, t.root]);
        at.push((i, i + 1));
    }
    (params, at)
}

/// Each tree's buffer table and root leaves: the first from `(table, root)`, the others from
/// their parameters `more` of the entry's arguments `a`.
fn tables_and_roots(
    b: &mut Builder<'_>,
    t: &Tys,
    a: &[ValueId],
    (table, root): (usize, usize),
    more: &[(usize, usize)],
) -> (Vec<ValueId>, Vec<Vec<ValueId>>) {
    let mut tables = Vec::new();
    let mut roots = Vec::new();
    for &(bi, ri) in std::iter::once(&(table, root)).chain(more) {
        tables.push(a[bi]);
        roots.push(root_leaves(b, t, a[bi], a[ri]));
    }
    (tables, roots)
}

/// `@scion_A_L(%B, %queries, %results, %begin, %end, %root) -> (i32)`, and for an algorithm
/// over several trees `(%B_k, %root_k)` for each other tree after them.
fn batch(m: &mut Module, sig: &EntrySig, t: &Tys, algo: &Algo) {
    let mut params = vec![t.ptr, t.ptr, t.ptr, t.u64, t.u64, t.root];
    let (extra, more) = more_trees(sig, t, params.len());
    params.extend(extra);
    let (f, entry, a) = new_func(m, sig.batch_fn(), &params, &[t.i32], false);
    // The buffer tables, the queries and the results do not overlap (docs/c-abi.md).
    let mut noalias = vec![0, 1, 2];
    noalias.extend(more.iter().map(|&(bi, _)| bi as i128));
    m.funcs[f].attrs.set("noalias", int_list(&noalias));
    let body = m.funcs[f].body;
    let head = m.add_block(body, &[t.u64]);
    let run = m.add_block(body, &[]);
    let next = m.add_block(body, &[]);
    let done = m.add_block(body, &[]);
    let i = m.blocks[head].args[0];
    let mut b = Builder::at_end(m, entry);
    let (tables, roots) = tables_and_roots(&mut b, t, &a, (0, 5), &more);
    b.lo_br(head, &[a[3]]);
    b.set_insertion_point_to_end(head);
    let more = b.lo_cmp(CmpPred::Lt, i, a[4]);
    b.lo_cond_br(more, (run, &[]), (done, &[]));
    b.set_insertion_point_to_end(run);
    let status = run_query(&mut b, sig, t, algo, &tables, a[1], a[2], i, &roots);
    match status {
        Some(s) => {
            let fail = b.m.add_block(body, &[]);
            let zero = b.lo_int(t.i32, 0);
            let bad = b.lo_cmp(CmpPred::Ne, s, zero);
            b.lo_cond_br(bad, (fail, &[]), (next, &[]));
            b.set_insertion_point_to_end(fail);
            b.lo_ret(&[s]);
        }
        None => {
            b.lo_br(next, &[]);
        }
    }
    b.set_insertion_point_to_end(next);
    let one = b.lo_int(t.u64, 1);
    let i1 = b.lo1(L::Add, &[i, one], t.u64);
    b.lo_br(head, &[i1]);
    b.set_insertion_point_to_end(done);
    let zero = b.lo_int(t.i32, 0);
    b.lo_ret(&[zero]);
}

/// `@scion_A_L_kernel(%B, %queries, %results, %n, %root, %status)`: one thread per query; over
/// several trees `(%B_k, %root_k)` for each other tree after them.
fn batch_kernel(m: &mut Module, sig: &EntrySig, t: &Tys, algo: &Algo) {
    let mut params = vec![t.ptr, t.ptr, t.ptr, t.u64, t.root, t.ptr];
    let (extra, more) = more_trees(sig, t, params.len());
    params.extend(extra);
    let name = format!("{}_kernel", sig.batch_fn());
    let (f, entry, a) = new_func(m, name, &params, &[], true);
    // The buffer tables, queries, results and status do not overlap (docs/c-abi.md).
    let mut noalias = vec![0, 1, 2, 5];
    noalias.extend(more.iter().map(|&(bi, _)| bi as i128));
    m.funcs[f].attrs.set("noalias", int_list(&noalias));
    let body = m.funcs[f].body;
    let run = m.add_block(body, &[]);
    let exit = m.add_block(body, &[]);
    let mut b = Builder::at_end(m, entry);
    let i = b.lo1(L::GlobalId, &[], t.u64);
    let inside = b.lo_cmp(CmpPred::Lt, i, a[3]);
    b.lo_cond_br(inside, (run, &[]), (exit, &[]));
    b.set_insertion_point_to_end(run);
    let (tables, roots) = tables_and_roots(&mut b, t, &a, (0, 4), &more);
    let status = run_query(&mut b, sig, t, algo, &tables, a[1], a[2], i, &roots);
    match status {
        Some(s) => {
            let fail = b.m.add_block(body, &[]);
            let zero = b.lo_int(t.i32, 0);
            let bad = b.lo_cmp(CmpPred::Ne, s, zero);
            b.lo_cond_br(bad, (fail, &[]), (exit, &[]));
            b.set_insertion_point_to_end(fail);
            b.lo_store(a[5], 0, s);
            b.lo_br(exit, &[]);
        }
        None => {
            b.lo_br(exit, &[]);
        }
    }
    b.set_insertion_point_to_end(exit);
    b.lo_ret(&[]);
}
