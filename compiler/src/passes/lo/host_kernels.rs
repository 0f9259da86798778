//! `lo-host-kernels`: turns the GPU kernels of a `lo` module into host functions, for the
//! host emulation of a launch (docs/gpu.md, "Checking the GPU pipeline without a GPU").
//! Input and output: a `lo` module.
//!
//! Each function with the attribute `kernel` loses it (keeping `export`) and gains a last
//! parameter `%id: u64`, the index of the thread running it; every `lo.global_id` in its body
//! becomes a use of `%id`. A host then launches a grid by calling the function once per
//! thread index. A `lo.global_id` outside a kernel has no thread index to become: E0972 names
//! the function. Nothing else changes, so the kernels compiled for the host run the very code
//! the PTX is made of, up to the instruction selection of NVPTX.

use scion_ir::diag::Diagnostic;
use scion_ir::entity::{FuncId, OpId};
use scion_ir::lo::Op as L;
use scion_ir::op::OpKind;
use scion_ir::rewrite::{erase_op, replace_all_uses, resolve_aliases};
use scion_ir::types::IntTy;
use scion_ir::{Module, Pass, PassCx, PassError};

/// The pass object.
pub struct LoHostKernels;

impl Pass for LoHostKernels {
    fn name(&self) -> &'static str {
        "lo-host-kernels"
    }

    fn summary(&self) -> &'static str {
        "GPU kernels to host functions taking the thread index as a last u64 parameter"
    }

    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        run(m).map_err(PassError::from)
    }
}

fn global_ids(m: &Module, f: FuncId) -> Vec<OpId> {
    m.regions[m.funcs[f].body]
        .blocks
        .iter()
        .flat_map(|&b| m.blocks[b].ops.iter().copied())
        .filter(|&o| m.ops[o].kind == OpKind::Lo(L::GlobalId))
        .collect()
}

/// Rewrites every kernel of `m`; returns whether there was one.
pub fn run(m: &mut Module) -> Result<bool, Diagnostic> {
    let funcs: Vec<FuncId> = m
        .func_order
        .iter()
        .copied()
        .filter(|&f| !m.is_declaration(f))
        .collect();
    let (kernels, others): (Vec<FuncId>, Vec<FuncId>) = funcs
        .into_iter()
        .partition(|&f| m.funcs[f].attrs.get("kernel").is_some());
    if let Some(&f) = others.iter().find(|&&f| !global_ids(m, f).is_empty()) {
        let op = global_ids(m, f)[0];
        let mut d = Diagnostic::error(
            "E0972",
            format!(
                "`lo.global_id` in `@{}`, which is not a kernel: only kernels are given the \
                 thread index on the host",
                m.funcs[f].name
            ),
        );
        if let Some(span) = m.span(op) {
            d = d.with_primary(span, "the thread index is read here");
        }
        return Err(d);
    }
    let u64t = m.types.int(IntTy::U64);
    for &f in &kernels {
        let entry = m
            .entry_block(f)
            .expect("a defined function has an entry block");
        let id = m.add_block_arg(entry, u64t);
        m.funcs[f].params.push(u64t);
        m.funcs[f].attrs.remove("kernel");
        for op in global_ids(m, f) {
            let r = m.result(op, 0);
            replace_all_uses(m, r, id);
            erase_op(m, op);
        }
    }
    resolve_aliases(m);
    Ok(!kernels.is_empty())
}
