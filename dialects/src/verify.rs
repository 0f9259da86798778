//! The structural verifier: checks that a module is well formed, then asks each dialect to check
//! its own ops. Input: a [`Module`]; output: `Ok(())` or every error found, each carrying the op
//! and its printed form, plus the offending functions printed with the errors above their ops.
//!
//! Invariants checked, in this order:
//! 1. Every id reachable from a live function exists in its arena, and every type is well
//!    formed (vector elements are scalars, lane counts are positive, ADT names are declared).
//! 2. Function names are unique; each function's body region exists, is owned by the function,
//!    and its entry block's arguments have the parameter types.
//! 3. Every region, block and op is listed exactly once, and its `parent` link names the op,
//!    region or block that lists it.
//! 4. Every value is defined exactly once, where its `ValueDef` says; no parser placeholder
//!    survives.
//! 5. Dominance: an operand is defined earlier in the same block, by an argument of that block,
//!    in a block that dominates it in the same region, or (the same rules applied outward) in an
//!    enclosing region. Structured regions have one block; CFG regions get a dominator tree
//!    (Cooper, Harvey and Kennedy's iterative algorithm), and an unreachable block sees only
//!    its own definitions and the enclosing regions'.
//! 6. Every block is non-empty and ends with a terminator, and terminators appear nowhere
//!    else; a structured region has exactly one block and no successors; successors name blocks
//!    of the same region with matching argument counts and types.
//! 7. Each op passes its dialect's `verify_op` (operand and result counts and types, attributes,
//!    region shapes, field indices against the ADT table).
//!
//! A failure on IR the compiler produced is a compiler bug: [`VerifyErrors::to_internal_error`]
//! turns it into an [`InternalError`] showing the IR. On IR a user wrote (`scion-opt` input),
//! [`VerifyErrors::to_diagnostics`] gives user-facing diagnostics (code `E0960`).

use crate::diag::{Diagnostic, Diagnostics, InternalError};
use crate::entity::{raw_index, BlockId, FuncId, OpId, RegionId, TypeId, ValueId};
use crate::module::{Module, RegionParent, ValueDef};
use crate::op::OpKind;
use crate::print;
use crate::types::Type;
use rustc_hash::{FxHashMap, FxHashSet};
use std::fmt;

/// One verifier finding.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VerifyError {
    /// The function it is in, if known.
    pub func: Option<FuncId>,
    /// The offending op, if the error is about one.
    pub op: Option<OpId>,
    /// What is wrong.
    pub message: String,
    /// The offending op's first printed line (empty when there is no op).
    pub printed: String,
}

/// Everything the verifier found, with the printed context.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VerifyErrors {
    /// The findings in discovery order.
    pub errors: Vec<VerifyError>,
    /// The functions with errors, printed with `// error: ...` lines above the offending ops.
    pub context: String,
}

impl VerifyErrors {
    /// An internal error (a compiler bug) naming `what` (e.g. the pass that produced the IR).
    pub fn to_internal_error(&self, what: &str) -> InternalError {
        let first = self
            .errors
            .first()
            .map_or(String::new(), |e| e.message.clone());
        InternalError::new(format!("{what}: IR verification failed: {first}"))
            .with_context(self.context.clone())
    }

    /// User-facing diagnostics, one per finding, labelled with the op's span when it has one.
    pub fn to_diagnostics(&self, m: &Module) -> Diagnostics {
        let mut out = Diagnostics::new();
        for e in &self.errors {
            let mut d = Diagnostic::error("E0960", format!("invalid IR: {}", e.message));
            if let Some(span) = e.op.and_then(|op| m.span(op)) {
                d = d.with_primary(span, "");
            }
            if !e.printed.is_empty() {
                d = d.with_note(format!("in `{}`", e.printed));
            }
            out.push(d);
        }
        out
    }
}

impl fmt::Display for VerifyErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for e in &self.errors {
            writeln!(f, "error: {}", e.message)?;
            if !e.printed.is_empty() {
                writeln!(f, "  in: {}", e.printed)?;
            }
        }
        write!(f, "{}", self.context)
    }
}

/// What a dialect's `verify_op` may know about the op's surroundings.
pub struct OpContext<'a> {
    /// Result types of the enclosing function (for `return`).
    pub func_results: &'a [TypeId],
    /// True when the op's block is a function body's block (not an op's region).
    pub in_func_body: bool,
}

/// Verifies the whole module.
pub fn verify(m: &Module) -> Result<(), VerifyErrors> {
    let mut v = Verifier::new(m);
    v.module();
    v.finish()
}

/// Verifies one function (and the module-level facts it relies on).
pub fn verify_func(m: &Module, f: FuncId) -> Result<(), VerifyErrors> {
    let mut v = Verifier::new(m);
    v.adts();
    v.func(f);
    v.finish()
}

struct Verifier<'m> {
    m: &'m Module,
    errors: Vec<VerifyError>,
    func: Option<FuncId>,
    func_results: Vec<TypeId>,
    seen_ops: FxHashSet<OpId>,
    seen_blocks: FxHashSet<BlockId>,
    seen_regions: FxHashSet<RegionId>,
    defined: FxHashSet<ValueId>,
    visible: FxHashSet<ValueId>,
    scope: Vec<ValueId>,
    good_types: FxHashSet<TypeId>,
}

impl<'m> Verifier<'m> {
    fn new(m: &'m Module) -> Verifier<'m> {
        Verifier {
            m,
            errors: Vec::new(),
            func: None,
            func_results: Vec::new(),
            seen_ops: FxHashSet::default(),
            seen_blocks: FxHashSet::default(),
            seen_regions: FxHashSet::default(),
            defined: FxHashSet::default(),
            visible: FxHashSet::default(),
            scope: Vec::new(),
            good_types: FxHashSet::default(),
        }
    }

    fn finish(self) -> Result<(), VerifyErrors> {
        if self.errors.is_empty() {
            return Ok(());
        }
        let mut by_func: FxHashMap<FuncId, FxHashMap<OpId, Vec<String>>> = FxHashMap::default();
        let mut order: Vec<FuncId> = Vec::new();
        let mut context = String::new();
        for e in &self.errors {
            match e.func {
                Some(f) => {
                    if !by_func.contains_key(&f) {
                        order.push(f);
                    }
                    let notes = by_func.entry(f).or_default();
                    if let Some(op) = e.op {
                        notes
                            .entry(op)
                            .or_default()
                            .push(format!("error: {}", e.message));
                    }
                }
                None => context.push_str(&format!("// error: {}\n", e.message)),
            }
        }
        for f in order {
            // Ids were checked before printing was needed; an unprintable function still gets
            // its errors listed above.
            if self.ids_printable(f) {
                for e in self
                    .errors
                    .iter()
                    .filter(|e| e.func == Some(f) && e.op.is_none())
                {
                    context.push_str(&format!("// error: {}\n", e.message));
                }
                context.push_str(&print::print_func_with_notes(self.m, f, &by_func[&f]));
            }
        }
        Err(VerifyErrors {
            errors: self.errors,
            context,
        })
    }

    fn ids_printable(&self, f: FuncId) -> bool {
        (raw_index(f) as usize) < self.m.funcs.len()
    }

    fn error(&mut self, op: Option<OpId>, message: impl Into<String>) {
        let printed = match op {
            Some(op) if self.has_op(op) && self.errors.len() < 100 => print::print_op(self.m, op)
                .lines()
                .next()
                .unwrap_or("")
                .trim()
                .to_string(),
            _ => String::new(),
        };
        self.errors.push(VerifyError {
            func: self.func,
            op,
            message: message.into(),
            printed,
        });
    }

    /// True when every id the dialect rules of `op` may follow exists: its regions, their
    /// blocks, the blocks' arguments, ops, and the operands and results of each last op.
    fn regions_sane(&self, op: OpId) -> bool {
        let m = self.m;
        m.ops[op].regions.iter().all(|&r| {
            self.has_region(r)
                && m.regions[r].blocks.iter().all(|&b| {
                    self.has_block(b)
                        && m.blocks[b]
                            .args
                            .iter()
                            .all(|&a| self.has_value(a) && m.types.contains(m.values[a].ty))
                        && m.blocks[b].ops.iter().all(|&o| self.has_op(o))
                        && m.blocks[b].ops.last().is_none_or(|&o| {
                            m.ops[o]
                                .operands
                                .iter()
                                .chain(m.ops[o].results.iter())
                                .all(|&v| self.has_value(v))
                        })
                })
        })
    }

    fn has_op(&self, id: OpId) -> bool {
        (raw_index(id) as usize) < self.m.ops.len()
    }
    fn has_block(&self, id: BlockId) -> bool {
        (raw_index(id) as usize) < self.m.blocks.len()
    }
    fn has_region(&self, id: RegionId) -> bool {
        (raw_index(id) as usize) < self.m.regions.len()
    }
    fn has_value(&self, id: ValueId) -> bool {
        (raw_index(id) as usize) < self.m.values.len()
    }

    fn module(&mut self) {
        let m = self.m;
        self.adts();
        let mut names = FxHashSet::default();
        for &f in &m.func_order {
            if (raw_index(f) as usize) >= m.funcs.len() {
                self.error(None, format!("function id {} does not exist", raw_index(f)));
                continue;
            }
            if !names.insert(m.funcs[f].name.as_str()) {
                self.error(
                    None,
                    format!("function `@{}` defined twice", m.funcs[f].name),
                );
            }
            self.func(f);
        }
    }

    fn adts(&mut self) {
        let m = self.m;
        for adt in &m.adts {
            let all = adt
                .shared
                .iter()
                .chain(adt.variants.iter().flat_map(|v| v.fields.iter()));
            for field in all {
                if !self.check_type(field.ty) {
                    self.error(
                        None,
                        format!(
                            "field `{}` of `{}` has an ill-formed type",
                            field.name, adt.name
                        ),
                    );
                }
            }
            let mut vnames = FxHashSet::default();
            for v in &adt.variants {
                if !vnames.insert(v.name.as_str()) {
                    self.error(
                        None,
                        format!("variant `{}` of `{}` declared twice", v.name, adt.name),
                    );
                }
            }
        }
    }

    /// True when `ty` exists and is well formed (see invariant 1).
    fn check_type(&mut self, ty: TypeId) -> bool {
        if self.good_types.contains(&ty) {
            return true;
        }
        let t = &self.m.types;
        if !t.contains(ty) {
            return false;
        }
        let ok = match t.get(ty) {
            Type::Bool | Type::Int(_) | Type::Float(_) | Type::Ptr => true,
            Type::Vector { elem, lanes } => {
                *lanes > 0
                    && t.contains(*elem)
                    && matches!(t.get(*elem), Type::Bool | Type::Int(_) | Type::Float(_))
            }
            Type::Tuple(elems) => elems.clone().into_iter().all(|e| self.check_type(e)),
            Type::Array { elem, .. }
            | Type::Set(elem)
            | Type::Option(elem)
            | Type::Ref(elem)
            | Type::View(elem) => {
                let e = *elem;
                self.check_type(e)
            }
            Type::Adt(name) => self.m.adt(name).is_some(),
        };
        if ok {
            self.good_types.insert(ty);
        }
        ok
    }

    fn check_value_type(&mut self, op: Option<OpId>, v: ValueId) {
        let ty = self.m.values[v].ty;
        if !self.check_type(ty) {
            let what = if self.m.types.contains(ty) {
                format!("ill-formed type {}", self.m.types.display(ty))
            } else {
                "a type id that does not exist".to_string()
            };
            self.error(op, format!("value has {what}"));
        }
    }

    fn func(&mut self, f: FuncId) {
        let m = self.m;
        self.func = Some(f);
        let func = &m.funcs[f];
        self.func_results = func.results.clone();
        for &t in func.params.iter().chain(func.results.iter()) {
            if !self.check_type(t) {
                self.error(
                    None,
                    format!("signature of `@{}` has an ill-formed type", func.name),
                );
                return;
            }
        }
        let body = func.body;
        if !self.has_region(body) {
            self.error(None, "function body region does not exist");
            return;
        }
        if m.regions[body].parent != Some(RegionParent::Func(f)) {
            self.error(None, "function body region is not owned by the function");
        }
        let Some(&entry) = m.regions[body].blocks.first() else {
            // A declaration: a signature without a body.
            self.func = None;
            return;
        };
        if self.has_block(entry) {
            let arg_tys: Vec<TypeId> = m.blocks[entry]
                .args
                .iter()
                .map(|&a| {
                    if self.has_value(a) {
                        m.values[a].ty
                    } else {
                        TypeId::from_raw(u32::MAX.into())
                    }
                })
                .collect();
            if arg_tys != func.params {
                self.error(
                    None,
                    "entry block arguments do not match the function's parameter types",
                );
            }
        }
        self.region(body, RegionParent::Func(f), false);
        self.func = None;
    }

    fn push_def(&mut self, v: ValueId) {
        self.visible.insert(v);
        self.scope.push(v);
    }

    fn pop_to(&mut self, mark: usize) {
        while self.scope.len() > mark {
            if let Some(v) = self.scope.pop() {
                self.visible.remove(&v);
            }
        }
    }

    /// Verifies a region owned by `owner`; `structured` regions must have exactly one block.
    fn region(&mut self, r: RegionId, owner: RegionParent, structured: bool) {
        let m = self.m;
        let owner_op = match owner {
            RegionParent::Op(op) => Some(op),
            RegionParent::Func(_) => None,
        };
        if !self.has_region(r) {
            self.error(owner_op, format!("region {} does not exist", raw_index(r)));
            return;
        }
        if !self.seen_regions.insert(r) {
            self.error(owner_op, "region listed twice");
            return;
        }
        if m.regions[r].parent != Some(owner) {
            self.error(owner_op, "region's parent link does not name its owner");
        }
        let blocks = m.regions[r].blocks.clone();
        if structured && blocks.len() != 1 {
            self.error(
                owner_op,
                format!(
                    "structured region must have exactly 1 block, has {}",
                    blocks.len()
                ),
            );
        }
        let mut valid = Vec::new();
        for &b in &blocks {
            if !self.has_block(b) {
                self.error(owner_op, format!("block {} does not exist", raw_index(b)));
            } else if !self.seen_blocks.insert(b) {
                self.error(owner_op, "block listed twice");
            } else {
                if m.blocks[b].parent != Some(r) {
                    self.error(owner_op, "block's parent link does not name its region");
                }
                valid.push(b);
            }
        }
        if valid.len() != blocks.len() || valid.is_empty() {
            for b in valid {
                let mark = self.scope.len();
                self.block(b, r, owner_op, structured);
                self.pop_to(mark);
            }
            return;
        }
        if valid.len() == 1 {
            let mark = self.scope.len();
            self.block(valid[0], r, owner_op, structured);
            self.pop_to(mark);
            return;
        }
        // A CFG region: visit blocks in dominator-tree pre-order, so each block sees exactly
        // the definitions of the blocks that dominate it.
        let (children, reachable) = dominator_tree(m, &valid);
        let mark = self.scope.len();
        let mut stack: Vec<(usize, usize, bool)> = vec![(0, mark, false)];
        while let Some((i, mark_i, done)) = stack.pop() {
            if done {
                self.pop_to(mark_i);
                continue;
            }
            let here = self.scope.len();
            self.block(valid[i], r, owner_op, structured);
            stack.push((i, here, true));
            for &c in children[i].iter().rev() {
                stack.push((c, 0, false));
            }
        }
        self.pop_to(mark);
        for (i, &b) in valid.iter().enumerate() {
            if !reachable[i] {
                let mark = self.scope.len();
                self.block(b, r, owner_op, structured);
                self.pop_to(mark);
            }
        }
    }

    fn block(&mut self, b: BlockId, r: RegionId, owner_op: Option<OpId>, structured: bool) {
        let m = self.m;
        for (i, &a) in m.blocks[b].args.iter().enumerate() {
            if !self.has_value(a) {
                self.error(
                    owner_op,
                    format!("block argument {} does not exist", raw_index(a)),
                );
                continue;
            }
            if m.values[a].def != ValueDef::BlockArg(b, i as u32) {
                self.error(
                    owner_op,
                    format!("block argument #{i} does not record its definition"),
                );
            }
            if !self.defined.insert(a) {
                self.error(owner_op, format!("block argument #{i} defined twice"));
            }
            self.check_value_type(owner_op, a);
            self.push_def(a);
        }
        let ops = m.blocks[b].ops.clone();
        if ops.is_empty() {
            self.error(owner_op, "block is empty (it needs a terminator)");
        }
        for (pos, &op) in ops.iter().enumerate() {
            if !self.has_op(op) {
                self.error(owner_op, format!("op {} does not exist", raw_index(op)));
                continue;
            }
            if !self.seen_ops.insert(op) {
                self.error(Some(op), "op listed twice");
                continue;
            }
            let o = &m.ops[op];
            if o.parent != Some(b) {
                self.error(Some(op), "op's parent link does not name its block");
            }
            let last = pos + 1 == ops.len();
            if o.kind.is_terminator() && !last {
                self.error(Some(op), "terminator in the middle of a block");
            }
            if last && !o.kind.is_terminator() {
                self.error(Some(op), "block does not end with a terminator");
            }
            self.op(op, r, structured);
        }
    }

    fn op(&mut self, op: OpId, r: RegionId, structured: bool) {
        let m = self.m;
        let o = &m.ops[op];
        let mut ids_ok = true;
        for &v in &o.operands {
            if !self.has_value(v) {
                self.error(
                    Some(op),
                    format!("operand value {} does not exist", raw_index(v)),
                );
                ids_ok = false;
            } else if !self.visible.contains(&v) {
                let why = if m.values[v].def == ValueDef::Forward {
                    "is a parser placeholder that was never defined"
                } else {
                    "does not dominate this use"
                };
                self.error(
                    Some(op),
                    format!(
                        "operand #{} {why}",
                        o.operands.iter().position(|&x| x == v).unwrap_or(0)
                    ),
                );
            }
        }
        if structured && !o.successors.is_empty() {
            self.error(
                Some(op),
                "successors are not allowed in a structured region",
            );
        }
        for s in &o.successors {
            if !self.has_block(s.block) {
                self.error(Some(op), "successor block does not exist");
                ids_ok = false;
                continue;
            }
            if m.blocks[s.block].parent != Some(r) {
                self.error(Some(op), "successor block is not in the same region");
            } else if m.regions[r].blocks.first() == Some(&s.block) {
                self.error(
                    Some(op),
                    "the entry block of a region cannot be a successor",
                );
            }
            let params = &m.blocks[s.block].args;
            if params.len() != s.args.len() {
                self.error(
                    Some(op),
                    format!(
                        "successor passes {} values to a block of {} arguments",
                        s.args.len(),
                        params.len()
                    ),
                );
            }
            for (&a, &p) in s.args.iter().zip(params.iter()) {
                if !self.has_value(a) || !self.has_value(p) {
                    ids_ok = false;
                    continue;
                }
                if !self.visible.contains(&a) {
                    self.error(Some(op), "successor argument does not dominate the branch");
                }
                if m.values[a].ty != m.values[p].ty {
                    self.error(
                        Some(op),
                        "successor argument type differs from the block argument's",
                    );
                }
            }
        }
        let structured_inner = o.kind.has_structured_regions();
        for &inner in &o.regions {
            let mark = self.scope.len();
            self.region(inner, RegionParent::Op(op), structured_inner);
            self.pop_to(mark);
        }
        for (i, &res) in o.results.iter().enumerate() {
            if !self.has_value(res) {
                self.error(
                    Some(op),
                    format!("result value {} does not exist", raw_index(res)),
                );
                ids_ok = false;
                continue;
            }
            if m.values[res].def != ValueDef::Result(op, i as u32) {
                self.error(
                    Some(op),
                    format!("result #{i} does not record its definition"),
                );
            }
            if !self.defined.insert(res) {
                self.error(Some(op), format!("result #{i} defined twice"));
            }
            self.check_value_type(Some(op), res);
            self.push_def(res);
        }
        if !ids_ok || !self.regions_sane(op) {
            return;
        }
        // Dialect rules may look inside types, so they only run on well-formed ones (an
        // ill-formed type was reported where its value is defined).
        let types: Vec<TypeId> = o
            .operands
            .iter()
            .chain(o.results.iter())
            .map(|&v| m.values[v].ty)
            .collect();
        if !types.into_iter().all(|t| self.check_type(t)) {
            return;
        }
        let in_func_body = matches!(m.regions[r].parent, Some(RegionParent::Func(_)));
        let results = self.func_results.clone();
        let cx = OpContext {
            func_results: &results,
            in_func_body,
        };
        let outcome = match o.kind {
            OpKind::Tree(k) => crate::tree::verify::verify_op(m, op, k, &cx),
            OpKind::Mem(k) => crate::mem::verify::verify_op(m, op, k, &cx),
        };
        if let Err(msg) = outcome {
            self.error(Some(op), msg);
        }
    }
}

/// The dominator tree of a CFG region whose blocks are `blocks` (entry first, all ids valid):
/// children lists by position, and which blocks are reachable from the entry.
pub fn dominator_tree(m: &Module, blocks: &[BlockId]) -> (Vec<Vec<usize>>, Vec<bool>) {
    let n = blocks.len();
    let index: FxHashMap<BlockId, usize> =
        blocks.iter().enumerate().map(|(i, &b)| (b, i)).collect();
    let succs: Vec<Vec<usize>> = blocks
        .iter()
        .map(|&b| {
            let last = m.blocks[b]
                .ops
                .last()
                .copied()
                .filter(|&o| (raw_index(o) as usize) < m.ops.len());
            last.map_or(Vec::new(), |o| {
                m.ops[o]
                    .successors
                    .iter()
                    .filter_map(|s| index.get(&s.block).copied())
                    .collect()
            })
        })
        .collect();
    // Reverse post-order by an iterative depth-first search from the entry.
    let mut post = Vec::with_capacity(n);
    let mut visited = vec![false; n];
    let mut stack = vec![(0usize, 0usize)];
    visited[0] = true;
    while let Some(&mut (b, ref mut next)) = stack.last_mut() {
        if let Some(&s) = succs[b].get(*next) {
            *next += 1;
            if !visited[s] {
                visited[s] = true;
                stack.push((s, 0));
            }
        } else {
            post.push(b);
            stack.pop();
        }
    }
    let rpo: Vec<usize> = post.iter().rev().copied().collect();
    let mut order = vec![usize::MAX; n];
    for (i, &b) in rpo.iter().enumerate() {
        order[b] = i;
    }
    let mut preds: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (b, ss) in succs.iter().enumerate() {
        if visited[b] {
            for &s in ss {
                preds[s].push(b);
            }
        }
    }
    let mut idom = vec![usize::MAX; n];
    idom[0] = 0;
    let mut changed = true;
    while changed {
        changed = false;
        for &b in rpo.iter().skip(1) {
            let mut new = usize::MAX;
            for &p in &preds[b] {
                if idom[p] == usize::MAX {
                    continue;
                }
                new = if new == usize::MAX {
                    p
                } else {
                    intersect(&idom, &order, p, new)
                };
            }
            if new != idom[b] {
                idom[b] = new;
                changed = true;
            }
        }
    }
    let mut children = vec![Vec::new(); n];
    for &b in rpo.iter().skip(1) {
        if idom[b] != usize::MAX {
            children[idom[b]].push(b);
        }
    }
    for c in &mut children {
        c.sort_unstable();
    }
    (children, visited)
}

fn intersect(idom: &[usize], order: &[usize], mut a: usize, mut b: usize) -> usize {
    while a != b {
        while order[a] > order[b] {
            a = idom[a];
        }
        while order[b] > order[a] {
            b = idom[b];
        }
    }
    a
}
