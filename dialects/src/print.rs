//! The text form: one generic syntax for every op of every dialect, close to MLIR's generic
//! operation form, so a later translation to upstream MLIR is mechanical.
//!
//! ```text
//! tree.type @AABB(low: vector<3xf32>, high: vector<3xf32>)
//! tree.type @BVH(bounds: !tree.adt<"AABB">) = Interior(left: !tree.adt<"BVH">, right: !tree.adt<"BVH">) | Leaf(n: u16)
//!
//! func @add(%0: f32, %1: f32) -> (f32) {
//!   %2 = "tree.add"(%0, %1) : (f32, f32) -> f32
//!   "tree.return"(%2) : (f32) -> ()
//! }
//! ```
//!
//! An op is `results = "dialect.name"(operands)[successors] (regions) {attributes} : (operand
//! types) -> result types`, each part after the operands printed only when present. A region is
//! `{ ^bbN(%arg: T): ops... }`. Values (`%N`) and blocks (`^bbN`) are numbered per function in
//! print order, never from arena indices, so the text does not change when a pass allocates and
//! drops temporaries. Spans are not printed. Input: a [`Module`]; output: text that
//! [`crate::parse::parse_module`] reads back to an equal module (`print ∘ parse ∘ print = print`).

use crate::attr::{quote, symbol_text, Attr, Attrs};
use crate::entity::{raw_index, BlockId, FuncId, OpId, RegionId, TypeId, ValueId};
use crate::module::{Field, Module};
use crate::types::FloatTy;
use rustc_hash::{FxHashMap, FxHashSet};
use std::fmt::Write;

/// Prints the whole module: ADT declarations, then functions, separated by blank lines.
pub fn print_module(m: &Module) -> String {
    let mut out = String::new();
    for adt in &m.adts {
        out.push_str(&print_adt(m, &adt.name));
        out.push('\n');
    }
    for l in &m.layouts {
        let _ = write!(out, "tree.layout @{}", symbol_text(&l.name));
        if let Some(a) = &l.adt {
            let _ = write!(out, " for @{}", symbol_text(a));
        }
        let _ = writeln!(out, " {}", quote(&l.source));
    }
    for (i, &f) in m.func_order.iter().enumerate() {
        if i > 0 || !m.adts.is_empty() || !m.layouts.is_empty() {
            out.push('\n');
        }
        out.push_str(&print_func(m, f));
    }
    out
}

/// Prints one ADT declaration (one line, no newline), or nothing for an unknown name.
pub fn print_adt(m: &Module, name: &str) -> String {
    let Some(adt) = m.adt(name) else {
        return String::new();
    };
    let mut out = format!("tree.type @{}(", symbol_text(&adt.name));
    print_fields(m, &adt.shared, &mut out);
    out.push(')');
    for (i, v) in adt.variants.iter().enumerate() {
        out.push_str(if i == 0 { " = " } else { " | " });
        out.push_str(&symbol_text(&v.name));
        out.push('(');
        print_fields(m, &v.fields, &mut out);
        out.push(')');
    }
    out
}

fn print_fields(m: &Module, fields: &[Field], out: &mut String) {
    for (i, f) in fields.iter().enumerate() {
        if i > 0 {
            out.push_str(", ");
        }
        let _ = write!(out, "{}: {}", symbol_text(&f.name), type_text(m, f.ty));
    }
}

fn type_text(m: &Module, ty: TypeId) -> String {
    if m.types.contains(ty) {
        m.types.display(ty).to_string()
    } else {
        format!("<<invalid type {}>>", raw_index(ty))
    }
}

/// Prints one function (ending with a newline).
pub fn print_func(m: &Module, f: FuncId) -> String {
    print_func_with_notes(m, f, &FxHashMap::default())
}

/// Prints one function with comment lines (`// <note>`) just before the ops named in `notes`;
/// the verifier uses it to show errors inside the IR.
pub fn print_func_with_notes(
    m: &Module,
    f: FuncId,
    notes: &FxHashMap<OpId, Vec<String>>,
) -> String {
    let mut p = Printer::new(m, notes);
    p.number_func(f);
    p.func(f);
    p.out
}

/// Prints one op (and its regions) as it would appear in its function, with values numbered as
/// in the whole function's printout when the op sits in a function.
pub fn print_op(m: &Module, op: OpId) -> String {
    let notes = FxHashMap::default();
    let mut p = Printer::new(m, &notes);
    if let Some(f) = m.func_of_op(op) {
        p.number_func(f);
    }
    p.op(op, 0);
    p.out.trim_end().to_string()
}

struct Printer<'a> {
    m: &'a Module,
    notes: &'a FxHashMap<OpId, Vec<String>>,
    values: FxHashMap<ValueId, u32>,
    blocks: FxHashMap<BlockId, u32>,
    seen: FxHashSet<OpId>,
    numbered: FxHashSet<OpId>,
    out: String,
}

impl<'a> Printer<'a> {
    fn new(m: &'a Module, notes: &'a FxHashMap<OpId, Vec<String>>) -> Printer<'a> {
        Printer {
            m,
            notes,
            values: FxHashMap::default(),
            blocks: FxHashMap::default(),
            seen: FxHashSet::default(),
            numbered: FxHashSet::default(),
            out: String::new(),
        }
    }

    fn has_region(&self, r: RegionId) -> bool {
        (raw_index(r) as usize) < self.m.regions.len()
    }
    fn has_block(&self, b: BlockId) -> bool {
        (raw_index(b) as usize) < self.m.blocks.len()
    }
    fn has_op(&self, o: OpId) -> bool {
        (raw_index(o) as usize) < self.m.ops.len()
    }
    fn has_value(&self, v: ValueId) -> bool {
        (raw_index(v) as usize) < self.m.values.len()
    }

    /// Numbers every value and block of the function in print order, so forward references
    /// (possible in CFG regions) print the same number as the definition.
    fn number_func(&mut self, f: FuncId) {
        let body = self.m.funcs[f].body;
        self.number_region(body);
    }

    fn number_region(&mut self, r: RegionId) {
        if !self.has_region(r) {
            return;
        }
        for &b in &self.m.regions[r].blocks {
            if self.has_block(b) && !self.blocks.contains_key(&b) {
                let n = self.blocks.len() as u32;
                self.blocks.insert(b, n);
            }
        }
        for &b in &self.m.regions[r].blocks {
            if !self.has_block(b) {
                continue;
            }
            for &a in &self.m.blocks[b].args {
                self.number_value(a);
            }
            for &op in &self.m.blocks[b].ops {
                if !self.has_op(op) || !self.numbered.insert(op) {
                    continue;
                }
                for &r in &self.m.ops[op].results {
                    self.number_value(r);
                }
                for &inner in &self.m.ops[op].regions {
                    self.number_region(inner);
                }
            }
        }
    }

    fn number_value(&mut self, v: ValueId) {
        if !self.values.contains_key(&v) {
            let n = self.values.len() as u32;
            self.values.insert(v, n);
        }
    }

    fn value(&self, v: ValueId) -> String {
        match self.values.get(&v) {
            Some(n) => format!("%{n}"),
            None => format!("%invalid{}", raw_index(v)),
        }
    }

    fn block(&self, b: BlockId) -> String {
        match self.blocks.get(&b) {
            Some(n) => format!("^bb{n}"),
            None => format!("^invalid{}", raw_index(b)),
        }
    }

    fn value_type(&self, v: ValueId) -> String {
        if self.has_value(v) {
            type_text(self.m, self.m.values[v].ty)
        } else {
            format!("<<invalid value {}>>", raw_index(v))
        }
    }

    fn indent(&mut self, depth: usize) {
        for _ in 0..depth {
            self.out.push_str("  ");
        }
    }

    fn func(&mut self, f: FuncId) {
        let m = self.m;
        let func = &m.funcs[f];
        let _ = write!(self.out, "func @{}(", symbol_text(&func.name));
        let body = func.body;
        let blocks: Vec<BlockId> = if self.has_region(body) {
            m.regions[body]
                .blocks
                .iter()
                .copied()
                .filter(|&b| self.has_block(b))
                .collect()
        } else {
            Vec::new()
        };
        if let Some(&entry) = blocks.first() {
            self.block_args(entry);
        } else {
            // A declaration (no body): the parameters have no names.
            let params: Vec<String> = func.params.iter().map(|&t| type_text(m, t)).collect();
            self.out.push_str(&params.join(", "));
        }
        self.out.push_str(") -> (");
        let results: Vec<String> = func.results.iter().map(|&t| type_text(m, t)).collect();
        self.out.push_str(&results.join(", "));
        self.out.push(')');
        if !func.attrs.is_empty() {
            self.out.push_str(" attributes");
            self.attr_dict(&func.attrs, false);
        }
        if blocks.is_empty() {
            self.out.push('\n');
            return;
        }
        self.out.push_str(" {\n");
        for (i, &b) in blocks.iter().enumerate() {
            if i > 0 {
                self.block_label(b, 0);
            }
            self.block_ops(b, 1);
        }
        self.out.push_str("}\n");
    }

    fn block_args(&mut self, b: BlockId) {
        let args = self.m.blocks[b].args.clone();
        for (i, &a) in args.iter().enumerate() {
            if i > 0 {
                self.out.push_str(", ");
            }
            let text = format!("{}: {}", self.value(a), self.value_type(a));
            self.out.push_str(&text);
        }
    }

    fn block_label(&mut self, b: BlockId, depth: usize) {
        self.indent(depth);
        let label = self.block(b);
        self.out.push_str(&label);
        if !self.m.blocks[b].args.is_empty() {
            self.out.push('(');
            self.block_args(b);
            self.out.push(')');
        }
        self.out.push_str(":\n");
    }

    fn block_ops(&mut self, b: BlockId, depth: usize) {
        let ops = self.m.blocks[b].ops.clone();
        for op in ops {
            self.op(op, depth);
        }
    }

    fn op(&mut self, op: OpId, depth: usize) {
        if !self.has_op(op) {
            self.indent(depth);
            let _ = writeln!(self.out, "<<invalid op {}>>", raw_index(op));
            return;
        }
        if !self.seen.insert(op) {
            self.indent(depth);
            let _ = writeln!(
                self.out,
                "<<op listed twice: {}>>",
                self.m.ops[op].kind.name()
            );
            return;
        }
        if let Some(notes) = self.notes.get(&op) {
            for n in notes {
                self.indent(depth);
                let _ = writeln!(self.out, "// {n}");
            }
        }
        let m = self.m;
        let o = &m.ops[op];
        self.indent(depth);
        if !o.results.is_empty() {
            let names: Vec<String> = o.results.iter().map(|&r| self.value(r)).collect();
            self.out.push_str(&names.join(", "));
            self.out.push_str(" = ");
        }
        self.out.push_str(&quote(&o.kind.name()));
        let operands: Vec<String> = o.operands.iter().map(|&v| self.value(v)).collect();
        let _ = write!(self.out, "({})", operands.join(", "));
        if !o.successors.is_empty() {
            self.out.push('[');
            for (i, s) in o.successors.iter().enumerate() {
                if i > 0 {
                    self.out.push_str(", ");
                }
                let label = self.block(s.block);
                self.out.push_str(&label);
                if !s.args.is_empty() {
                    let names: Vec<String> = s.args.iter().map(|&v| self.value(v)).collect();
                    let tys: Vec<String> = s.args.iter().map(|&v| self.value_type(v)).collect();
                    let _ = write!(self.out, "({} : {})", names.join(", "), tys.join(", "));
                }
            }
            self.out.push(']');
        }
        if !o.regions.is_empty() {
            self.out.push_str(" (");
            for (i, &r) in o.regions.iter().enumerate() {
                if i > 0 {
                    self.out.push_str(", ");
                }
                self.region(r, depth);
            }
            self.out.push(')');
        }
        if !o.attrs.is_empty() {
            // Float attributes of an op computing in f32 print in their short f32 spelling.
            let f32_hint = o.results.len() == 1
                && self.has_value(o.results[0])
                && m.types.contains(m.values[o.results[0]].ty)
                && m.types
                    .as_float(m.types.scalar_of(m.values[o.results[0]].ty))
                    == Some(FloatTy::F32);
            self.attr_dict(&o.attrs, f32_hint);
        }
        let tys: Vec<String> = o.operands.iter().map(|&v| self.value_type(v)).collect();
        let _ = write!(self.out, " : ({}) -> ", tys.join(", "));
        let res: Vec<String> = o.results.iter().map(|&v| self.value_type(v)).collect();
        if res.len() == 1 {
            self.out.push_str(&res[0]);
        } else {
            let _ = write!(self.out, "({})", res.join(", "));
        }
        self.out.push('\n');
    }

    /// ` {name = value, ...}`
    fn attr_dict(&mut self, attrs: &Attrs, f32_hint: bool) {
        self.out.push_str(" {");
        for (i, (name, a)) in attrs.iter().enumerate() {
            if i > 0 {
                self.out.push_str(", ");
            }
            self.out.push_str(&symbol_text(name));
            if *a != Attr::Unit {
                self.out.push_str(" = ");
                a.print_with_hint(&self.m.types, &mut self.out, f32_hint);
            }
        }
        self.out.push('}');
    }

    fn region(&mut self, r: RegionId, depth: usize) {
        self.out.push_str("{\n");
        if self.has_region(r) {
            let blocks = self.m.regions[r].blocks.clone();
            for b in blocks {
                if !self.has_block(b) {
                    continue;
                }
                self.block_label(b, depth);
                self.block_ops(b, depth + 1);
            }
        }
        self.indent(depth);
        self.out.push('}');
    }
}
