//! The `tree` dialect: the layout-agnostic level that the front end (`irgen`) produces from the
//! typed AST (paper §3-§5: the traversal language before destructor specialization).
//!
//! Trees are algebraic data types declared in the module's ADT table; algorithms read them only
//! through `tree.match` (destructuring a variant into block arguments), `tree.field` (a shared
//! field), and `tree.is`; nothing here knows where a field sits in memory. Control flow is
//! structured: `tree.if`, `tree.match` and `tree.foreach` own single-block regions ending in
//! `tree.yield`, and `tree.return` leaves the function from any depth. Mutable state exists only
//! behind `!tree.ref<T>` (`mut` parameters and `tree.var` cells) through `tree.load` and
//! `tree.store`. Short-circuit `&&` and `||` are `tree.if` ops with an `i1` result.
//!
//! [`ops`] lists the op kinds, [`verify`] their rules; this module adds builder shorthands.

pub mod directed;
pub mod intrinsic;
pub mod ops;
pub mod quant;
pub mod scalar;
pub mod snapped;
pub mod sort;
pub mod verify;

pub use intrinsic::Intrinsic;
pub use ops::{CmpPred, Op};

use crate::attr::Attr;
use crate::builder::{Builder, OpSpec};
use crate::entity::{OpId, TypeId, ValueId};
use crate::types::Type;

/// `tree` shorthands on the builder. Each inserts at the cursor and returns the new op's single
/// result (or the op when it has several or none).
impl Builder<'_> {
    /// `tree.const` of an integer (`i1` takes 0 or 1).
    pub fn const_int(&mut self, ty: TypeId, v: i128) -> ValueId {
        let value = if matches!(self.m.types.get(ty), Type::Bool) {
            Attr::Bool(v != 0)
        } else {
            Attr::Int(v)
        };
        let op = self.insert(OpSpec::new(Op::Const).attr("value", value).results(&[ty]));
        self.result(op, 0)
    }

    /// `tree.const` of a float type, holding `v` (rounded to the type when narrower).
    pub fn const_float(&mut self, ty: TypeId, v: f64) -> ValueId {
        let v = match self.m.types.as_float(ty) {
            Some(crate::types::FloatTy::F32) => v as f32 as f64,
            _ => v,
        };
        let op = self.insert(
            OpSpec::new(Op::Const)
                .attr("value", Attr::float(v))
                .results(&[ty]),
        );
        self.result(op, 0)
    }

    /// `tree.const` of `i1`.
    pub fn const_bool(&mut self, v: bool) -> ValueId {
        let ty = self.m.types.bool();
        let op = self.insert(
            OpSpec::new(Op::Const)
                .attr("value", Attr::Bool(v))
                .results(&[ty]),
        );
        self.result(op, 0)
    }

    /// A binary op whose result has the left operand's type (`add`, `and`, `shl`, ...).
    pub fn binary(&mut self, op: Op, lhs: ValueId, rhs: ValueId) -> ValueId {
        let ty = self.value_type(lhs);
        self.build1(op, &[lhs, rhs], ty)
    }

    /// A unary op whose result has the operand's type (`neg`, `not`, `bitnot`).
    pub fn unary(&mut self, op: Op, v: ValueId) -> ValueId {
        let ty = self.value_type(v);
        self.build1(op, &[v], ty)
    }

    /// `tree.cmp {pred}`; the result is `i1`, or a vector of `i1` for vector operands.
    pub fn cmp(&mut self, pred: CmpPred, lhs: ValueId, rhs: ValueId) -> ValueId {
        let operand = self.value_type(lhs);
        let i1 = self.m.types.bool();
        let ty = match self.m.types.lanes(operand) {
            Some(n) => self.m.types.vector(i1, n),
            None => i1,
        };
        let op = self.insert(
            OpSpec::new(Op::Cmp)
                .operands(&[lhs, rhs])
                .attr("pred", Attr::str(pred.name()))
                .results(&[ty]),
        );
        self.result(op, 0)
    }

    /// `tree.field {name, index}` reading shared field `name` of an ADT value. `None` when the
    /// value is not of a declared ADT or has no such shared field.
    pub fn field(&mut self, v: ValueId, name: &str) -> Option<ValueId> {
        let ty = self.value_type(v);
        let (index, field_ty) = {
            let adt = self.m.adt_of_type(ty)?;
            let (i, f) = adt.shared_field(name)?;
            (i, f.ty)
        };
        let op = self.insert(
            OpSpec::new(Op::Field)
                .operands(&[v])
                .attr("name", Attr::str(name))
                .attr("index", Attr::Int(index as i128))
                .results(&[field_ty]),
        );
        Some(self.result(op, 0))
    }

    /// `tree.ctor` of `adt_ty` (a record when `variant` is `None`) from its fields.
    pub fn ctor(&mut self, adt_ty: TypeId, variant: Option<&str>, fields: &[ValueId]) -> ValueId {
        let mut spec = OpSpec::new(Op::Ctor).operands(fields).results(&[adt_ty]);
        if let Some(v) = variant {
            spec = spec.attr("variant", Attr::str(v));
        }
        let op = self.insert(spec);
        self.result(op, 0)
    }

    /// `tree.call @callee`, with the result types taken from the callee's signature when the
    /// function exists in the module, from `result_types` otherwise (for calls built before the
    /// callee).
    pub fn call(&mut self, callee: &str, args: &[ValueId], result_types: &[TypeId]) -> OpId {
        let results = match self.m.func_by_name(callee) {
            Some(f) => self.m.funcs[f].results.clone(),
            None => result_types.to_vec(),
        };
        self.insert(
            OpSpec::new(Op::Call)
                .operands(args)
                .attr("callee", Attr::Sym(callee.to_string()))
                .results(&results),
        )
    }

    /// `tree.intrinsic {name}` with one result.
    pub fn intrinsic(
        &mut self,
        intrinsic: Intrinsic,
        args: &[ValueId],
        result_type: TypeId,
    ) -> ValueId {
        let op = self.insert(
            OpSpec::new(Op::Intrinsic)
                .operands(args)
                .attr("name", Attr::str(intrinsic.name()))
                .results(&[result_type]),
        );
        self.result(op, 0)
    }

    /// `tree.yield(values)`.
    pub fn yield_(&mut self, values: &[ValueId]) -> OpId {
        self.build(Op::Yield, values, &[])
    }

    /// `tree.return(values)`.
    pub fn ret(&mut self, values: &[ValueId]) -> OpId {
        self.build(Op::Return, values, &[])
    }

    /// `tree.if` with results: `then_body` and `else_body` fill the two regions and must end
    /// them with `tree.yield` (or `tree.return`).
    pub fn if_(
        &mut self,
        cond: ValueId,
        result_types: &[TypeId],
        then_body: impl FnOnce(&mut Builder<'_>),
        else_body: impl FnOnce(&mut Builder<'_>),
    ) -> OpId {
        let then_r = self.region(&[], |b, _| then_body(b));
        let else_r = self.region(&[], |b, _| else_body(b));
        self.insert(
            OpSpec::new(Op::If)
                .operands(&[cond])
                .results(result_types)
                .region(then_r)
                .region(else_r),
        )
    }

    /// `tree.match` on an ADT value with one arm per entry of `arms` (a variant name or `"_"`).
    /// Each arm's block gets the variant's fields (shared first) as arguments; a wildcard arm
    /// gets none. `arm_body` is called with the arm's position and its block arguments.
    /// Returns `None` when the scrutinee is not of a declared ADT or names an unknown variant.
    pub fn match_(
        &mut self,
        scrutinee: ValueId,
        arms: &[&str],
        result_types: &[TypeId],
        mut arm_body: impl FnMut(&mut Builder<'_>, usize, &[ValueId]),
    ) -> Option<OpId> {
        let ty = self.value_type(scrutinee);
        let mut arm_args: Vec<Vec<TypeId>> = Vec::new();
        {
            let adt = self.m.adt_of_type(ty)?;
            for arm in arms {
                if *arm == "_" {
                    arm_args.push(Vec::new());
                } else {
                    arm_args.push(adt.fields_of(Some(arm))?.iter().map(|f| f.ty).collect());
                }
            }
        }
        let mut spec = OpSpec::new(Op::Match)
            .operands(&[scrutinee])
            .results(result_types);
        for (i, tys) in arm_args.iter().enumerate() {
            let r = self.region(tys, |b, args| arm_body(b, i, args));
            spec = spec.region(r);
        }
        let names = arms.iter().map(|a| Attr::str(*a)).collect();
        Some(self.insert(spec.attr("arms", Attr::List(names))))
    }

    /// `tree.foreach` over an array, slice or set; `body` gets the element and must end the
    /// region with `tree.yield()`. Returns `None` when `array` is neither.
    pub fn foreach(
        &mut self,
        array: ValueId,
        body: impl FnOnce(&mut Builder<'_>, ValueId),
    ) -> Option<OpId> {
        let elem = match self.m.types.get(self.value_type(array)) {
            Type::Array { elem, .. } | Type::Set(elem) => *elem,
            _ => return None,
        };
        let r = self.region(&[elem], |b, args| body(b, args[0]));
        Some(self.insert(OpSpec::new(Op::Foreach).operands(&[array]).region(r)))
    }

    /// `tree.select(cond, a, b)`.
    pub fn select(&mut self, cond: ValueId, a: ValueId, b: ValueId) -> ValueId {
        let ty = self.value_type(a);
        self.build1(Op::Select, &[cond, a, b], ty)
    }

    /// `tree.cast` (`as`) to `to`.
    pub fn cast(&mut self, v: ValueId, to: TypeId) -> ValueId {
        self.build1(Op::Cast, &[v], to)
    }

    /// `tree.bitcast` (`to`) to `to`.
    pub fn bitcast(&mut self, v: ValueId, to: TypeId) -> ValueId {
        self.build1(Op::Bitcast, &[v], to)
    }

    /// `tree.tuple` of the values.
    pub fn tuple(&mut self, elems: &[ValueId]) -> ValueId {
        let tys = elems.iter().map(|&e| self.value_type(e)).collect();
        let ty = self.m.types.tuple(tys);
        self.build1(Op::Tuple, elems, ty)
    }

    /// `tree.extract {index}`; `None` when `tuple` is not a tuple with that many elements.
    pub fn extract(&mut self, tuple: ValueId, index: usize) -> Option<ValueId> {
        let elem = match self.m.types.get(self.value_type(tuple)) {
            Type::Tuple(elems) => *elems.get(index)?,
            _ => return None,
        };
        let spec = OpSpec::new(Op::Extract)
            .operands(&[tuple])
            .attr("index", Attr::Int(index as i128));
        let op = self.insert(spec.results(&[elem]));
        Some(self.result(op, 0))
    }

    /// `tree.insert {index}`: `tuple` with element `index` replaced by `value`.
    pub fn insert_elem(&mut self, tuple: ValueId, index: usize, value: ValueId) -> ValueId {
        let ty = self.value_type(tuple);
        let spec = OpSpec::new(Op::Insert)
            .operands(&[tuple, value])
            .attr("index", Attr::Int(index as i128));
        let op = self.insert(spec.results(&[ty]));
        self.result(op, 0)
    }

    /// `tree.vector` from scalars (at least one).
    pub fn vector(&mut self, lanes: &[ValueId]) -> Option<ValueId> {
        let elem = self.value_type(*lanes.first()?);
        let ty = self.m.types.vector(elem, lanes.len() as u32);
        Some(self.build1(Op::Vector, lanes, ty))
    }

    /// `tree.lane {index}` of a vector; `None` when `v` is not a vector.
    pub fn lane(&mut self, v: ValueId, index: u32) -> Option<ValueId> {
        let elem = match self.m.types.get(self.value_type(v)) {
            Type::Vector { elem, .. } => *elem,
            _ => return None,
        };
        let spec = OpSpec::new(Op::Lane)
            .operands(&[v])
            .attr("index", Attr::Int(index as i128));
        let op = self.insert(spec.results(&[elem]));
        Some(self.result(op, 0))
    }

    /// `tree.index` into an array or vector; `None` for other types.
    pub fn index(&mut self, container: ValueId, i: ValueId) -> Option<ValueId> {
        let elem = match self.m.types.get(self.value_type(container)) {
            Type::Array { elem, .. } | Type::Vector { elem, .. } => *elem,
            _ => return None,
        };
        Some(self.build1(Op::Index, &[container, i], elem))
    }

    /// `tree.slice` `[lo, hi)` of an array; `None` for other types.
    pub fn slice(&mut self, array: ValueId, lo: ValueId, hi: ValueId) -> Option<ValueId> {
        let elem = match self.m.types.get(self.value_type(array)) {
            Type::Array { elem, .. } | Type::Set(elem) => *elem,
            _ => return None,
        };
        let ty = self.m.types.array(elem, None);
        Some(self.build1(Op::Slice, &[array, lo, hi], ty))
    }

    /// `tree.bits {lo, hi}`: bits `[lo, hi)` of an integer as `result_type`.
    pub fn bits(&mut self, v: ValueId, lo: u32, hi: u32, result_type: TypeId) -> ValueId {
        let spec = OpSpec::new(Op::Bits)
            .operands(&[v])
            .attr("lo", Attr::Int(lo as i128))
            .attr("hi", Attr::Int(hi as i128))
            .results(&[result_type]);
        let op = self.insert(spec);
        self.result(op, 0)
    }

    /// `tree.is {variant}`.
    pub fn is_variant(&mut self, v: ValueId, variant: &str) -> ValueId {
        let i1 = self.m.types.bool();
        let op = self.insert(
            OpSpec::new(Op::Is)
                .operands(&[v])
                .attr("variant", Attr::str(variant))
                .results(&[i1]),
        );
        self.result(op, 0)
    }

    /// `tree.var`: a new mutable cell holding `init`.
    pub fn var(&mut self, init: ValueId) -> ValueId {
        let ty = self.value_type(init);
        let r = self.m.types.reference(ty);
        self.build1(Op::Var, &[init], r)
    }

    /// `tree.load` through a reference; `None` when `r` is not a `!tree.ref<T>`.
    pub fn load(&mut self, r: ValueId) -> Option<ValueId> {
        let pointee = match self.m.types.get(self.value_type(r)) {
            Type::Ref(t) => *t,
            _ => return None,
        };
        Some(self.build1(Op::Load, &[r], pointee))
    }

    /// `tree.store` of `value` through `r`.
    pub fn store(&mut self, r: ValueId, value: ValueId) -> OpId {
        self.build(Op::Store, &[r, value], &[])
    }
}
