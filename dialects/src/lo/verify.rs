//! Per-op rules of the `lo` dialect: every operand and result is a scalar or `ptr`, counts and
//! types per [`super::ops::Op`], attributes, successors only on branches, callee signatures.
//!
//! Called by [`crate::verify::verify`] after the structural checks (which already match
//! successor arguments against block arguments and check dominance in the CFG).

use super::ops::Op;
use crate::attr::Attr;
use crate::entity::{OpId, TypeId};
use crate::module::Module;

use crate::types::{FloatTy, IntTy, Type};
use crate::verify::OpContext;

type VResult = Result<(), String>;

fn require(ok: bool, msg: impl FnOnce() -> String) -> VResult {
    if ok {
        Ok(())
    } else {
        Err(msg())
    }
}

/// True for the types a `lo` value may have.
pub fn is_lo_type(m: &Module, ty: TypeId) -> bool {
    matches!(
        m.types.get(ty),
        Type::Bool | Type::Int(_) | Type::Float(FloatTy::F32 | FloatTy::F64) | Type::Ptr
    )
}

/// Checks one `lo` op.
pub fn verify_op(m: &Module, id: OpId, kind: Op, cx: &OpContext<'_>) -> VResult {
    let o = &m.ops[id];
    let name = format!("lo.{}", kind.mnemonic());
    let ot: Vec<TypeId> = o.operands.iter().map(|&v| m.values[v].ty).collect();
    let rt: Vec<TypeId> = o.results.iter().map(|&v| m.values[v].ty).collect();
    let t = &m.types;
    let show = |ty: TypeId| t.display(ty).to_string();
    require(o.regions.is_empty(), || {
        format!("`{name}` takes no regions")
    })?;
    let want_succ = match kind {
        Op::Br => 1,
        Op::CondBr => 2,
        _ => 0,
    };
    require(o.successors.len() == want_succ, || {
        format!("`{name}` takes {want_succ} successors")
    })?;
    for &ty in ot.iter().chain(rt.iter()) {
        require(is_lo_type(m, ty), || {
            format!("`{name}`: {} is not a scalar or ptr type", show(ty))
        })?;
    }
    let counts = |n: usize, r: usize| {
        require(ot.len() == n && rt.len() == r, || {
            format!(
                "`{name}` takes {n} operands and {r} results, found {} and {}",
                ot.len(),
                rt.len()
            )
        })
    };
    let is_int = |ty: TypeId| t.as_int(ty).is_some();
    let is_float = |ty: TypeId| t.as_float(ty).is_some();
    let is_bool = |ty: TypeId| matches!(t.get(ty), Type::Bool);
    let is_ptr = |ty: TypeId| matches!(t.get(ty), Type::Ptr);
    let all_same = || ot.iter().chain(rt.iter()).all(|&x| x == rt[0]);
    let offset = || {
        require(o.int_attr("offset").is_some(), || {
            format!("`{name}` needs an integer `offset`")
        })
    };
    match kind {
        Op::Const => {
            counts(0, 1)?;
            match (o.attr("value"), t.get(rt[0])) {
                (Some(Attr::Bool(_)), Type::Bool) => Ok(()),
                (Some(Attr::Int(_)), Type::Int(_) | Type::Ptr) => Ok(()),
                (Some(Attr::Float(_)), Type::Float(_)) => Ok(()),
                _ => Err(format!(
                    "`value` must be a constant of the result type {}",
                    show(rt[0])
                )),
            }
        }
        Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Rem => {
            counts(2, 1)?;
            require(all_same() && (is_int(rt[0]) || is_float(rt[0])), || {
                format!("`{name}` needs two numbers of the result type")
            })
        }
        Op::And | Op::Or | Op::Xor => {
            counts(2, 1)?;
            require(all_same() && (is_int(rt[0]) || is_bool(rt[0])), || {
                format!("`{name}` needs two integers or i1 of the result type")
            })
        }
        Op::Shl | Op::Shr => {
            counts(2, 1)?;
            require(ot[0] == rt[0] && is_int(rt[0]) && is_int(ot[1]), || {
                format!("`{name}` needs (T, U) -> T on integers")
            })
        }
        Op::Neg | Op::Abs => {
            counts(1, 1)?;
            require(all_same() && (is_int(rt[0]) || is_float(rt[0])), || {
                format!("`{name}` needs a number")
            })
        }
        Op::BitNot | Op::Popcount | Op::Clz | Op::Ctz => {
            counts(1, 1)?;
            require(all_same() && is_int(rt[0]), || {
                format!("`{name}` needs an integer")
            })
        }
        Op::Not => {
            counts(1, 1)?;
            require(all_same() && is_bool(rt[0]), || {
                format!("`{name}` needs an i1")
            })
        }
        Op::Min | Op::Max => {
            counts(2, 1)?;
            require(all_same() && (is_int(rt[0]) || is_float(rt[0])), || {
                format!("`{name}` needs two numbers of the result type")
            })
        }
        Op::Sqrt | Op::Floor | Op::Ceil | Op::Trunc | Op::NextUp | Op::NextDown => {
            counts(1, 1)?;
            require(all_same() && is_float(rt[0]), || {
                format!("`{name}` needs a float")
            })
        }
        Op::AddRd | Op::AddRu | Op::MulRd | Op::MulRu => {
            counts(2, 1)?;
            let f32t = matches!(t.get(rt[0]), Type::Float(FloatTy::F32));
            require(all_same() && f32t, || {
                format!("`{name}` needs two f32 of the result type (directed rounding is f32 only)")
            })
        }
        Op::Fma => {
            counts(3, 1)?;
            require(all_same() && is_float(rt[0]), || {
                format!("`{name}` needs three floats")
            })
        }
        Op::Cmp => {
            counts(2, 1)?;
            let pred = o.pred();
            require(pred.is_some(), || {
                format!("`{name}` needs `pred` = eq, ne, lt, le, gt or ge")
            })?;
            require(ot[0] == ot[1] && is_bool(rt[0]), || {
                format!("`{name}` compares two values of one type to i1")
            })
        }
        Op::Select => {
            counts(3, 1)?;
            require(is_bool(ot[0]) && ot[1] == rt[0] && ot[2] == rt[0], || {
                format!("`{name}` takes (i1, T, T) -> T")
            })
        }
        Op::Cast => {
            counts(1, 1)?;
            let num = |ty| is_int(ty) || is_float(ty) || is_bool(ty);
            require(num(ot[0]) && num(rt[0]), || {
                format!("`{name}` converts between numbers")
            })
        }
        Op::Bitcast => {
            counts(1, 1)?;
            require(
                t.bit_width(ot[0]).is_some() && t.bit_width(ot[0]) == t.bit_width(rt[0]),
                || format!("`{name}` needs types of equal width"),
            )
        }
        Op::Load => {
            counts(1, 1)?;
            offset()?;
            require(is_ptr(ot[0]), || format!("`{name}` loads through a ptr"))?;
            match o.attr("global") {
                None => Ok(()),
                Some(Attr::Bool(_)) => require(is_ptr(rt[0]), || {
                    format!("`{name}`: `global` marks a loaded ptr, not {}", show(rt[0]))
                }),
                Some(_) => Err(format!("`{name}`: `global` is a bool")),
            }
        }
        Op::Store => {
            counts(2, 0)?;
            offset()?;
            require(is_ptr(ot[0]), || format!("`{name}` stores through a ptr"))
        }
        Op::PtrAdd => {
            counts(2, 1)?;
            require(is_ptr(ot[0]) && is_int(ot[1]) && is_ptr(rt[0]), || {
                format!("`{name}` takes (ptr, integer) -> ptr")
            })
        }
        Op::StackSlot => {
            counts(0, 1)?;
            let size = o.int_attr("size");
            require(size.is_some_and(|s| s > 0) && is_ptr(rt[0]), || {
                format!("`{name}` needs a positive `size` and gives a ptr")
            })?;
            require(
                o.int_attr("align")
                    .is_none_or(|a| a > 0 && (a & (a - 1)) == 0),
                || format!("`{name}`: `align` must be a power of two"),
            )
        }
        Op::GlobalId => {
            counts(0, 1)?;
            require(matches!(t.get(rt[0]), Type::Int(IntTy::U64)), || {
                format!("`{name}` gives a u64")
            })
        }
        Op::Call => {
            let callee = o.callee();
            let Some(f) = callee.and_then(|c| m.func_by_name(c)) else {
                return Err(format!("`{name}` needs `callee` naming a function"));
            };
            let func = &m.funcs[f];
            require(func.params == ot && func.results == rt, || {
                format!("`{name}` does not match the signature of @{}", func.name)
            })
        }
        Op::Br => counts(0, 0),
        Op::CondBr => require(ot.len() == 1 && rt.is_empty() && is_bool(ot[0]), || {
            format!("`{name}` takes one i1 condition")
        }),
        Op::Return => require(rt.is_empty() && ot == cx.func_results, || {
            format!("`{name}` values do not match the function's result types")
        }),
    }
}
