//! Per-op rules of the `tree` dialect: operand and result counts and types, attributes, region
//! shapes and terminators, and field indices checked against the module's ADT table.
//!
//! Called by [`crate::verify::verify`] after the structural checks, so ids are valid here. Each rule is
//! the one documented on the op's variant in [`super::ops::Op`].

use super::ops::{CmpPred, Op};
use crate::attr::Attr;
use crate::entity::{OpId, TypeId};
use crate::module::Module;
use crate::op::Operation;
use crate::types::{FloatTy, Type};
use crate::verify::OpContext;

type VResult = Result<(), String>;

/// Checks one `tree` op.
pub fn verify_op(m: &Module, id: OpId, kind: Op, cx: &OpContext<'_>) -> VResult {
    let o = &m.ops[id];
    let ot: Vec<TypeId> = o.operands.iter().map(|&v| m.values[v].ty).collect();
    let rt: Vec<TypeId> = o.results.iter().map(|&v| m.values[v].ty).collect();
    let t = &m.types;
    let show = |ty: TypeId| t.display(ty).to_string();
    if !kind.has_regions() && !o.regions.is_empty() {
        return Err(format!("`tree.{}` takes no regions", kind.mnemonic()));
    }
    if !o.successors.is_empty() {
        return Err(format!("`tree.{}` takes no successors", kind.mnemonic()));
    }
    match kind {
        Op::Const => {
            counts(&ot, &rt, 0, 1)?;
            let ty = rt[0];
            match (o.attr("value"), t.get(ty)) {
                (Some(Attr::Bool(_)), Type::Bool) => Ok(()),
                (Some(Attr::Int(v)), Type::Int(it)) => {
                    let (lo, hi) = it.range();
                    // Unsigned bit patterns of a signed type are accepted too (`0xFFFFFFFF : i32`).
                    let unsigned_hi = (1i128 << it.bits()) - 1;
                    if (lo..=hi).contains(v) || (0..=unsigned_hi).contains(v) {
                        Ok(())
                    } else {
                        Err(format!("constant {v} does not fit in {}", it.name()))
                    }
                }
                (Some(Attr::Float(bits)), Type::Float(ft)) => {
                    let v = f64::from_bits(*bits);
                    if *ft == FloatTy::F32 && !v.is_nan() && (v as f32) as f64 != v {
                        Err(format!("constant {v} is not exactly representable as f32"))
                    } else {
                        Ok(())
                    }
                }
                _ => Err(format!(
                    "`value` must be a constant of the result type {}",
                    show(ty)
                )),
            }
        }
        Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Rem => {
            counts(&ot, &rt, 2, 1)?;
            same(&ot[0], &[ot[1], rt[0]], &show)?;
            require(is_numeric(m, ot[0]), || {
                format!("arithmetic on non-numeric type {}", show(ot[0]))
            })
        }
        Op::Neg => {
            counts(&ot, &rt, 1, 1)?;
            same(&ot[0], &[rt[0]], &show)?;
            require(is_numeric(m, ot[0]), || {
                format!("negation of non-numeric type {}", show(ot[0]))
            })
        }
        Op::And | Op::Or | Op::Xor => {
            counts(&ot, &rt, 2, 1)?;
            same(&ot[0], &[ot[1], rt[0]], &show)?;
            require(t.is_integer_like(t.scalar_of(ot[0])), || {
                format!("bitwise op on {}", show(ot[0]))
            })
        }
        Op::BitNot => {
            counts(&ot, &rt, 1, 1)?;
            same(&ot[0], &[rt[0]], &show)?;
            require(t.is_integer_like(t.scalar_of(ot[0])), || {
                format!("bitwise not of {}", show(ot[0]))
            })
        }
        Op::Not => {
            counts(&ot, &rt, 1, 1)?;
            same(&ot[0], &[rt[0]], &show)?;
            require(matches!(t.get(t.scalar_of(ot[0])), Type::Bool), || {
                format!("logical not of {}", show(ot[0]))
            })
        }
        Op::Shl | Op::Shr => {
            counts(&ot, &rt, 2, 1)?;
            same(&ot[0], &[rt[0]], &show)?;
            let ok = t.as_int(t.scalar_of(ot[0])).is_some()
                && t.as_int(t.scalar_of(ot[1])).is_some()
                && t.lanes(ot[0]) == t.lanes(ot[1]);
            require(ok, || {
                format!("shift of {} by {}", show(ot[0]), show(ot[1]))
            })
        }
        Op::Cmp => {
            counts(&ot, &rt, 2, 1)?;
            same(&ot[0], &[ot[1]], &show)?;
            let pred = o.pred().ok_or("`pred` must be one of eq ne lt le gt ge")?;
            let scalar = t.scalar_of(ot[0]);
            let ordered = !matches!(pred, CmpPred::Eq | CmpPred::Ne);
            if !(is_numeric(m, ot[0]) || matches!(t.get(scalar), Type::Bool) && !ordered) {
                return Err(format!("`{}` comparison of {}", pred.name(), show(ot[0])));
            }
            let want_bool = match (t.get(rt[0]), t.lanes(ot[0])) {
                (Type::Bool, None) => true,
                (Type::Vector { elem, lanes }, Some(n)) => {
                    *lanes == n && matches!(t.get(*elem), Type::Bool)
                }
                _ => false,
            };
            require(want_bool, || {
                format!(
                    "comparison result must be i1 (per lane), not {}",
                    show(rt[0])
                )
            })
        }
        Op::Select => {
            counts(&ot, &rt, 3, 1)?;
            same(&ot[1], &[ot[2], rt[0]], &show)?;
            let ok = match t.get(ot[0]) {
                Type::Bool => true,
                Type::Vector { elem, lanes } => {
                    matches!(t.get(*elem), Type::Bool) && t.lanes(ot[1]) == Some(*lanes)
                }
                _ => false,
            };
            require(ok, || {
                format!("select condition must be i1, not {}", show(ot[0]))
            })
        }
        Op::Cast => {
            counts(&ot, &rt, 1, 1)?;
            let ok = t.is_scalar(t.scalar_of(ot[0]))
                && t.is_scalar(t.scalar_of(rt[0]))
                && t.lanes(ot[0]) == t.lanes(rt[0]);
            require(ok, || {
                format!("cannot cast {} to {}", show(ot[0]), show(rt[0]))
            })
        }
        Op::Bitcast => {
            counts(&ot, &rt, 1, 1)?;
            let (a, b) = (t.bit_width(ot[0]), t.bit_width(rt[0]));
            require(a.is_some() && a == b, || {
                format!(
                    "bitcast between {} and {} of different widths",
                    show(ot[0]),
                    show(rt[0])
                )
            })
        }
        Op::Tuple => {
            counts(&ot, &rt, ot.len(), 1)?;
            let ok = matches!(t.get(rt[0]), Type::Tuple(elems) if *elems == ot);
            require(ok, || {
                format!(
                    "result must be the tuple of the operand types, not {}",
                    show(rt[0])
                )
            })
        }
        Op::Array => {
            counts(&ot, &rt, ot.len(), 1)?;
            let ok = !ot.is_empty()
                && ot.iter().all(|&x| x == ot[0])
                && matches!(t.get(rt[0]), Type::Array { elem, len: Some(n) }
                    if *elem == ot[0] && *n as usize == ot.len());
            require(ok, || {
                format!(
                    "result must be the array of its (equally typed, at least one) operands, not {}",
                    show(rt[0])
                )
            })
        }
        Op::Extract => {
            counts(&ot, &rt, 1, 1)?;
            let elems = tuple_elems(m, ot[0])?;
            let i = index_attr(o, "index", elems.len())?;
            same(&elems[i], &[rt[0]], &show)
        }
        Op::Insert => {
            counts(&ot, &rt, 2, 1)?;
            let elems = tuple_elems(m, ot[0])?;
            let i = index_attr(o, "index", elems.len())?;
            same(&elems[i], &[ot[1]], &show)?;
            same(&ot[0], &[rt[0]], &show)
        }
        Op::Vector => {
            if ot.is_empty() {
                return Err("`tree.vector` needs at least one lane".into());
            }
            counts(&ot, &rt, ot.len(), 1)?;
            let ok = matches!(t.get(rt[0]), Type::Vector { elem, lanes } if *lanes as usize == ot.len() && ot.iter().all(|x| x == elem));
            require(ok, || {
                format!(
                    "result {} does not match {} lanes of the operand type",
                    show(rt[0]),
                    ot.len()
                )
            })
        }
        Op::Lane => {
            counts(&ot, &rt, 1, 1)?;
            let Type::Vector { elem, lanes } = t.get(ot[0]) else {
                return Err(format!("lane of non-vector {}", show(ot[0])));
            };
            index_attr(o, "index", *lanes as usize)?;
            same(elem, &[rt[0]], &show)
        }
        Op::Field => {
            counts(&ot, &rt, 1, 1)?;
            let adt = m
                .adt_of_type(ot[0])
                .ok_or_else(|| format!("field of non-ADT {}", show(ot[0])))?;
            let i = index_attr(o, "index", adt.shared.len())?;
            let name = o.str_attr("name").ok_or("`name` must be a string")?;
            let f = &adt.shared[i];
            if f.name != name {
                return Err(format!(
                    "shared field #{i} of `{}` is `{}`, not `{name}`",
                    adt.name, f.name
                ));
            }
            same(&f.ty, &[rt[0]], &show)
        }
        Op::Ctor => {
            counts(&ot, &rt, ot.len(), 1)?;
            let adt = m
                .adt_of_type(rt[0])
                .ok_or_else(|| format!("constructor of non-ADT {}", show(rt[0])))?;
            let variant = match o.attr("variant") {
                None => None,
                Some(Attr::Str(v)) => Some(v.as_str()),
                Some(_) => return Err("`variant` must be a string".into()),
            };
            let fields = adt.fields_of(variant).ok_or_else(|| match variant {
                Some(v) => format!("`{}` has no variant `{v}`", adt.name),
                None => format!("`{}` is a sum: the constructor needs a `variant`", adt.name),
            })?;
            let want: Vec<TypeId> = fields.iter().map(|f| f.ty).collect();
            require(want == ot, || {
                format!(
                    "constructor operands do not match the fields of `{}`",
                    adt.name
                )
            })
        }
        Op::Is => {
            counts(&ot, &rt, 1, 1)?;
            let adt = m
                .adt_of_type(ot[0])
                .ok_or_else(|| format!("variant test of non-ADT {}", show(ot[0])))?;
            let v = o.str_attr("variant").ok_or("`variant` must be a string")?;
            adt.variant(v)
                .ok_or_else(|| format!("`{}` has no variant `{v}`", adt.name))?;
            require(matches!(t.get(rt[0]), Type::Bool), || {
                "variant test result must be i1".into()
            })
        }
        Op::Match => verify_match(m, o, &ot, &rt),
        Op::If => {
            if ot.len() != 1 || !matches!(t.get(ot[0]), Type::Bool) {
                return Err("`tree.if` takes one i1 condition".into());
            }
            if o.regions.len() != 2 {
                return Err(format!(
                    "`tree.if` needs then and else regions, has {}",
                    o.regions.len()
                ));
            }
            for &r in &o.regions {
                region_shape(m, r, &[], &rt)?;
            }
            Ok(())
        }
        Op::Foreach => {
            counts(&ot, &rt, 1, 0)?;
            let elem = match t.get(ot[0]) {
                Type::Array { elem, .. } | Type::Set(elem) | Type::View(elem) => elem,
                _ => {
                    return Err(format!(
                        "foreach over {}, not an array, set or view",
                        show(ot[0])
                    ))
                }
            };
            if o.regions.len() != 1 {
                return Err("`tree.foreach` needs one body region".into());
            }
            let r = o.regions[0];
            let Some(&b) = m.regions[r].blocks.first() else {
                return Err("foreach body has no block".into());
            };
            let args: Vec<TypeId> = m.blocks[b].args.iter().map(|&a| m.values[a].ty).collect();
            let ok = match args.as_slice() {
                [e] => e == elem,
                [e, i] => e == elem && t.as_int(*i).is_some(),
                _ => false,
            };
            if !ok {
                return Err(format!(
                    "foreach body takes the element ({}) and optionally an integer index",
                    show(*elem)
                ));
            }
            region_shape(m, r, &args, &[])
        }
        Op::Index => {
            counts(&ot, &rt, 2, 1)?;
            let elem = match t.get(ot[0]) {
                Type::Array { elem, .. } | Type::Vector { elem, .. } | Type::View(elem) => *elem,
                _ => return Err(format!("index into {}", show(ot[0]))),
            };
            require(t.as_int(ot[1]).is_some(), || {
                format!("index must be an integer, not {}", show(ot[1]))
            })?;
            same(&elem, &[rt[0]], &show)
        }
        Op::Slice => {
            counts(&ot, &rt, 3, 1)?;
            let Type::Array { elem, .. } = t.get(ot[0]) else {
                return Err(format!("slice of {}", show(ot[0])));
            };
            require(
                t.as_int(ot[1]).is_some() && t.as_int(ot[2]).is_some(),
                || "slice bounds must be integers".into(),
            )?;
            let ok = matches!(t.get(rt[0]), Type::Array { elem: e, len: None } if e == elem);
            require(ok, || {
                format!("slice result must be array<? x {}>", show(*elem))
            })
        }
        Op::Bits => {
            let res_ok = rt.len() == 1 && t.as_int(rt[0]).is_some();
            if !res_ok {
                return Err("`tree.bits` has one integer result".into());
            }
            let width = match ot.first().map(|&x| t.get(x)) {
                Some(Type::Int(it)) => it.bits() as i128,
                _ => return Err("`tree.bits` reads an integer".into()),
            };
            match (o.int_attr("lo"), o.int_attr("hi")) {
                (Some(lo), Some(hi)) => {
                    counts(&ot, &rt, 1, 1)?;
                    require(0 <= lo && lo < hi && hi <= width, || {
                        format!("bit range [{lo}, {hi}) outside 0..{width}")
                    })
                }
                (None, None) => {
                    counts(&ot, &rt, 3, 1)?;
                    require(
                        t.as_int(ot[1]).is_some() && t.as_int(ot[2]).is_some(),
                        || "bit bounds must be integers".into(),
                    )
                }
                _ => Err("`tree.bits` takes both `lo` and `hi` attributes or neither".into()),
            }
        }
        Op::Call => {
            let callee = o.callee().ok_or("`callee` must be a symbol")?;
            let f = m
                .func_by_name(callee)
                .ok_or_else(|| format!("call to unknown function `@{callee}`"))?;
            let func = &m.funcs[f];
            require(func.params == ot, || {
                format!("argument types do not match `@{callee}`'s parameters")
            })?;
            require(func.results == rt, || {
                format!("result types do not match `@{callee}`'s results")
            })
        }
        Op::Intrinsic => {
            let intrinsic = super::intrinsic::Intrinsic::of(o)?;
            if rt.len() != 1 {
                return Err("an intrinsic has one result".into());
            }
            intrinsic.check(m, &ot, rt[0])
        }
        Op::Var => {
            counts(&ot, &rt, 1, 1)?;
            require(*t.get(rt[0]) == Type::Ref(ot[0]), || {
                format!(
                    "`tree.var` of {} gives !tree.ref<{}>",
                    show(ot[0]),
                    show(ot[0])
                )
            })
        }
        Op::Load => {
            counts(&ot, &rt, 1, 1)?;
            require(*t.get(ot[0]) == Type::Ref(rt[0]), || {
                format!("load of {} as {}", show(ot[0]), show(rt[0]))
            })
        }
        Op::Store => {
            counts(&ot, &rt, 2, 0)?;
            require(*t.get(ot[0]) == Type::Ref(ot[1]), || {
                format!("store of {} into {}", show(ot[1]), show(ot[0]))
            })
        }
        Op::This => counts(&ot, &rt, 0, 1),
        Op::BuildStore => {
            counts(&ot, &rt, 1, 0)?;
            field_attr(o)
        }
        Op::BuildStoreBits => {
            counts(&ot, &rt, 1, 0)?;
            require(t.as_int(ot[0]).is_some(), || {
                format!("`this[lo:hi] = v` of {}", show(ot[0]))
            })?;
            match (o.int_attr("lo"), o.int_attr("hi")) {
                (Some(lo), Some(hi)) if 0 <= lo && lo < hi && hi <= 64 => Ok(()),
                _ => Err("`tree.build_store_bits` needs bits `lo < hi <= 64`".into()),
            }
        }
        Op::BuildChild => {
            counts(&ot, &rt, 1, 1)?;
            // One child's logical index, or an array of them (an array of children builds
            // into the array of their references).
            let ok = match (t.get(ot[0]), t.get(rt[0])) {
                (Type::Array { elem, len: Some(n) }, Type::Array { len: Some(k), .. }) => {
                    t.as_int(*elem).is_some() && n == k
                }
                _ => t.as_int(ot[0]).is_some(),
            };
            require(ok, || {
                format!(
                    "child index of type {} building {}",
                    show(ot[0]),
                    show(rt[0])
                )
            })?;
            field_attr(o)
        }
        Op::BuildLoad => {
            counts(&ot, &rt, 0, 1)?;
            field_attr(o)
        }
        Op::ChildField => {
            counts(&ot, &rt, 1, 1)?;
            require(t.as_int(ot[0]).is_some(), || {
                format!("child index of type {}", show(ot[0]))
            })?;
            field_attr(o)
        }
        Op::Append => {
            counts(&ot, &rt, 2, 1)?;
            let ok = matches!(t.get(ot[0]), Type::Array { .. } | Type::View(_))
                && t.as_int(ot[1]).is_some()
                && t.as_int(rt[0]).is_some();
            require(ok, || {
                format!(
                    "append takes (array, integer) -> integer, not ({}, {}) -> {}",
                    show(ot[0]),
                    show(ot[1]),
                    show(rt[0])
                )
            })?;
            field_attr(o)
        }
        Op::Yield => {
            counts(&ot, &rt, ot.len(), 0)?;
            if cx.in_func_body {
                return Err("`tree.yield` outside a region of `if`, `match` or `foreach`".into());
            }
            // The enclosing op checks the yielded types against its results.
            Ok(())
        }
        Op::Return => {
            counts(&ot, &rt, ot.len(), 0)?;
            require(ot == cx.func_results, || {
                "returned types do not match the function's results".into()
            })
        }
    }
}

fn field_attr(o: &Operation) -> VResult {
    match o.attr("field") {
        Some(Attr::Str(_)) => Ok(()),
        _ => Err("build ops need a string `field`".into()),
    }
}

fn require(ok: bool, msg: impl FnOnce() -> String) -> VResult {
    if ok {
        Ok(())
    } else {
        Err(msg())
    }
}

fn counts(ot: &[TypeId], rt: &[TypeId], operands: usize, results: usize) -> VResult {
    if ot.len() != operands {
        return Err(format!("expected {operands} operands, found {}", ot.len()));
    }
    if rt.len() != results {
        return Err(format!("expected {results} results, found {}", rt.len()));
    }
    Ok(())
}

fn same(want: &TypeId, others: &[TypeId], show: &dyn Fn(TypeId) -> String) -> VResult {
    for &o in others {
        if o != *want {
            return Err(format!("type mismatch: {} vs {}", show(*want), show(o)));
        }
    }
    Ok(())
}

fn is_numeric(m: &Module, ty: TypeId) -> bool {
    let s = m.types.scalar_of(ty);
    matches!(m.types.get(s), Type::Int(_) | Type::Float(_))
}

fn tuple_elems(m: &Module, ty: TypeId) -> Result<Vec<TypeId>, String> {
    match m.types.get(ty) {
        Type::Tuple(e) => Ok(e.clone()),
        _ => Err(format!("expected a tuple, found {}", m.types.display(ty))),
    }
}

fn index_attr(o: &Operation, name: &str, len: usize) -> Result<usize, String> {
    match o.int_attr(name) {
        Some(i) if i >= 0 && (i as usize) < len => Ok(i as usize),
        Some(i) => Err(format!("`{name}` {i} out of range 0..{len}")),
        None => Err(format!("`{name}` must be an integer")),
    }
}

/// Checks a structured region: one block with arguments of `args`, ending with `tree.yield`
/// of `yields` or with `tree.return`.
fn region_shape(
    m: &Module,
    r: crate::entity::RegionId,
    args: &[TypeId],
    yields: &[TypeId],
) -> VResult {
    let Some(&b) = m.regions[r].blocks.first() else {
        return Err("region has no block".into());
    };
    let got: Vec<TypeId> = m.blocks[b].args.iter().map(|&a| m.values[a].ty).collect();
    if got != args {
        return Err(format!(
            "region block takes {} arguments of the wrong types or count",
            got.len()
        ));
    }
    let Some(&last) = m.blocks[b].ops.last() else {
        return Err("region block is empty".into());
    };
    let term = &m.ops[last];
    match term.tree_op() {
        Some(Op::Return) => Ok(()),
        Some(Op::Yield) => {
            let ys: Vec<TypeId> = term.operands.iter().map(|&v| m.values[v].ty).collect();
            require(ys == yields, || {
                format!(
                    "region yields {} values of the wrong types; the op has {} results",
                    ys.len(),
                    yields.len()
                )
            })
        }
        _ => Err("region must end with `tree.yield` or `tree.return`".into()),
    }
}

fn verify_match(m: &Module, o: &Operation, ot: &[TypeId], rt: &[TypeId]) -> VResult {
    if ot.len() != 1 {
        return Err("`tree.match` takes one operand".into());
    }
    let adt = m
        .adt_of_type(ot[0])
        .ok_or_else(|| format!("match on non-ADT {}", m.types.display(ot[0])))?;
    if adt.is_record() {
        return Err(format!("match on record `{}` (use `tree.field`)", adt.name));
    }
    let arms = o
        .attr("arms")
        .and_then(Attr::as_list)
        .ok_or("`arms` must be a list of variant names")?;
    if arms.len() != o.regions.len() || arms.is_empty() {
        return Err(format!(
            "{} arm names for {} regions",
            arms.len(),
            o.regions.len()
        ));
    }
    let mut covered = vec![false; adt.variants.len()];
    let mut wildcard = false;
    for (arm, &r) in arms.iter().zip(&o.regions) {
        let name = arm.as_str().ok_or("arm names must be strings")?;
        let args: Vec<TypeId> = if name == "_" {
            if wildcard {
                return Err("two wildcard arms".into());
            }
            wildcard = true;
            let b = m.regions[r].blocks.first().copied();
            let n = b.map_or(0, |b| m.blocks[b].args.len());
            if n == 0 {
                Vec::new()
            } else {
                adt.shared.iter().map(|f| f.ty).collect()
            }
        } else {
            let (i, _) = adt
                .variant(name)
                .ok_or_else(|| format!("`{}` has no variant `{name}`", adt.name))?;
            if covered[i] {
                return Err(format!("variant `{name}` matched twice"));
            }
            covered[i] = true;
            adt.fields_of(Some(name))
                .unwrap_or_default()
                .iter()
                .map(|f| f.ty)
                .collect()
        };
        region_shape(m, r, &args, rt).map_err(|e| format!("arm `{name}`: {e}"))?;
    }
    if !wildcard {
        if let Some(i) = covered.iter().position(|c| !c) {
            return Err(format!(
                "match is not exhaustive: variant `{}` has no arm",
                adt.variants[i].name
            ));
        }
    }
    Ok(())
}
