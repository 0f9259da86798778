//! The builtins of `tree.intrinsic`, as the interpreter computes them.
//!
//! Floats compute in their own precision. `min`/`max` on floats are IEEE `minNum`/`maxNum`
//! (a NaN operand yields the other one, as the prelude's slab test needs); `rsqrt` is
//! `1 / sqrt`. `dot` sums the lane products left to right without
//! fusing (`((a0*b0 + a1*b1) + a2*b2)`), `length` is `sqrt(dot(v, v))`, `normalize` divides
//! each lane by the length, `cross` is the usual 3-lane formula, `hmin`/`hmax`/`hsum` fold the
//! lanes left to right. `sqrt` and `fma` are correctly rounded. The quantization builtins (`frame_origin`, `frame_step`,
//! `quant_lo`, `quant_hi`) are [`crate::tree::quant`]'s reference functions, lane by lane; the
//! directed-rounding ones (`fadd_rd` .. `fmul_ru`, `f32` lanes) [`crate::tree::directed`]'s,
//! the snapped-grid ones (`sg_bins`, `sg_code_up`, `sg_code_down`) [`crate::tree::snapped`]'s.

use super::tree::{lanewise1, lanewise2, scalar_type};
use super::Val;
use crate::entity::TypeId;
use crate::module::Module;
use crate::tree::directed;
use crate::tree::intrinsic::Intrinsic;
use crate::tree::quant;
use crate::tree::scalar::{canon32, canon64, Scalar};
use crate::tree::snapped;
use crate::types::{IntTy, Type};
use std::rc::Rc;

type R = Result<Val, String>;

/// `f32op`/`f64op` lane-wise, as IEEE 754 operations on one operand: a NaN operand gives
/// itself, quieted (the payload kept, as `sqrtss`/`roundss` and AArch64 do; Rust's software
/// `trunc` would keep a signaling NaN signaling).
fn float1(a: &Val, f32op: fn(f32) -> f32, f64op: fn(f64) -> f64) -> R {
    lanewise1(a, &|x| match x {
        Scalar::F32(v) if v.is_nan() => Ok(Scalar::F32(f32::from_bits(v.to_bits() | 1 << 22))),
        Scalar::F64(v) if v.is_nan() => Ok(Scalar::F64(f64::from_bits(v.to_bits() | 1 << 51))),
        Scalar::F32(v) => Ok(Scalar::F32(f32op(v))),
        Scalar::F64(v) => Ok(Scalar::F64(f64op(v))),
        _ => Err("expects floats".into()),
    })
}

fn lanes(v: &Val) -> Result<&[Val], String> {
    match v {
        Val::Vector(l) => Ok(l),
        _ => Err("expects a vector".into()),
    }
}

fn add(a: &Val, b: &Val) -> R {
    lanewise2(a, b, &|x, y| {
        crate::tree::scalar::binary(crate::tree::Op::Add, x, y).ok_or_else(|| "bad operands".into())
    })
}

fn mul(a: &Val, b: &Val) -> R {
    lanewise2(a, b, &|x, y| {
        crate::tree::scalar::binary(crate::tree::Op::Mul, x, y).ok_or_else(|| "bad operands".into())
    })
}

fn sub(a: &Val, b: &Val) -> R {
    lanewise2(a, b, &|x, y| {
        crate::tree::scalar::binary(crate::tree::Op::Sub, x, y).ok_or_else(|| "bad operands".into())
    })
}

fn dot(a: &Val, b: &Val) -> R {
    let (x, y) = (lanes(a)?, lanes(b)?);
    let mut acc = mul(
        x.first().ok_or("empty vector")?,
        y.first().ok_or("empty vector")?,
    )?;
    for (p, q) in x.iter().zip(y).skip(1) {
        acc = add(&acc, &mul(p, q)?)?;
    }
    Ok(acc)
}

/// `a < b` for `sort`: numbers by `<`, tuples component by component.
fn less(a: &Val, b: &Val) -> Result<bool, String> {
    use crate::tree::scalar::compare;
    use crate::tree::CmpPred;
    let parts = |v: &Val| -> Vec<Val> {
        match v {
            Val::Tuple(cs) => cs.clone(),
            other => vec![other.clone()],
        }
    };
    for (x, y) in parts(a).iter().zip(&parts(b)) {
        let (Some(x), Some(y)) = (x.scalar(), y.scalar()) else {
            return Err("`sort` compares numbers".into());
        };
        if compare(CmpPred::Lt, x, y) == Some(true) {
            return Ok(true);
        }
        if compare(CmpPred::Eq, x, y) != Some(true) {
            return Ok(false);
        }
    }
    Ok(false)
}

fn fold_lanes(v: &Val, f: &dyn Fn(&Val, &Val) -> R) -> R {
    let l = lanes(v)?;
    let mut acc = l.first().ok_or("empty vector")?.clone();
    for x in &l[1..] {
        acc = f(&acc, x)?;
    }
    Ok(acc)
}

fn min_max(a: &Val, b: &Val, max: bool) -> R {
    lanewise2(a, b, &|x, y| {
        Ok(match (x, y) {
            (Scalar::Int(p, t), Scalar::Int(q, _)) => {
                Scalar::Int(if max { p.max(q) } else { p.min(q) }, t)
            }
            (Scalar::F32(p), Scalar::F32(q)) => Scalar::F32(min_max_num(p, q, max)),
            (Scalar::F64(p), Scalar::F64(q)) => Scalar::F64(min_max_num(p, q, max)),
            _ => return Err("expects numbers of one type".into()),
        })
    })
}

/// IEEE `minNum`/`maxNum`, spelled out so every backend can match it bit for bit: the other
/// operand when one is NaN (`q` when both are), else the smaller (larger) one, and `p` on ties
/// (so `min(+0, -0)` is `+0`). Rust's `f32::min` leaves the zero case unspecified.
fn min_max_num<F: PartialOrd + Copy>(p: F, q: F, max: bool) -> F {
    #[allow(clippy::eq_op)]
    let p_nan = p != p;
    if p_nan {
        return q;
    }
    #[allow(clippy::eq_op)]
    let q_nan = q != q;
    if q_nan {
        return p;
    }
    if (max && q > p) || (!max && q < p) {
        q
    } else {
        p
    }
}

/// Evaluates `intrinsic` on `args`, giving a value of type `result`.
pub fn eval(m: &Module, intrinsic: Intrinsic, args: &[Val], result: TypeId) -> R {
    use Intrinsic as I;
    let name = intrinsic.name();
    let one = || {
        args.first()
            .ok_or_else(|| format!("`{name}` needs an operand"))
    };
    let two = || match args {
        [a, b, ..] => Ok((a, b)),
        _ => Err(format!("`{name}` needs two operands")),
    };
    match intrinsic {
        I::Abs => lanewise1(one()?, &|x| {
            Ok(match x {
                Scalar::Int(v, t) => Scalar::Int(t.wrap(v.abs()), t),
                Scalar::F32(v) => Scalar::F32(v.abs()),
                Scalar::F64(v) => Scalar::F64(v.abs()),
                Scalar::Bool(_) => return Err("expects numbers".into()),
            })
        }),
        I::Min | I::Max => {
            let (a, b) = two()?;
            min_max(a, b, intrinsic == I::Max)
        }
        I::Sqrt => float1(one()?, f32::sqrt, f64::sqrt),
        // `sqrt` passes a NaN's payload on (as the hardware's does); the division makes the
        // canonical NaN, as every division does.
        I::Rsqrt => lanewise1(one()?, &|x| match x {
            Scalar::F32(v) => Ok(canon32(1.0 / v.sqrt())),
            Scalar::F64(v) => Ok(canon64(1.0 / v.sqrt())),
            _ => Err("expects floats".into()),
        }),
        I::Floor => float1(one()?, f32::floor, f64::floor),
        I::Ceil => float1(one()?, f32::ceil, f64::ceil),
        I::Trunc => float1(one()?, f32::trunc, f64::trunc),
        I::Fma => match args {
            [a, b, c] => fma3(a, b, c),
            _ => Err("`fma` needs three operands".into()),
        },
        I::FaddRd | I::FaddRu | I::FsubRd | I::FsubRu | I::FmulRd | I::FmulRu => {
            let (a, b) = two()?;
            let dir = if name.ends_with("_ru") {
                directed::Round::Up
            } else {
                directed::Round::Down
            };
            let f = match &name[..4] {
                "fadd" => directed::add,
                "fsub" => directed::sub,
                _ => directed::mul,
            };
            lanewise2(a, b, &|x, y| match (x, y) {
                (Scalar::F32(x), Scalar::F32(y)) => Ok(Scalar::F32(f(x, y, dir))),
                _ => Err("directed rounding takes f32 lanes".into()),
            })
        }
        I::WithAxis => match args {
            // A lane index outside the vector changes nothing (as the lowering's selects).
            [Val::Vector(v), Val::Int(k, _), x] => {
                let mut out = v.clone();
                if let Some(slot) = usize::try_from(*k).ok().and_then(|i| out.get_mut(i)) {
                    *slot = x.clone();
                }
                Ok(Val::Vector(out))
            }
            _ => Err("`with_axis` takes a vector, an integer lane index and an element".into()),
        },
        I::FrameOrigin => lanewise1(one()?, &|x| match x {
            Scalar::F32(v) => Ok(Scalar::F32(quant::frame_origin(v))),
            _ => Err("expects f32 lanes".into()),
        }),
        I::FrameStep | I::SgBins => match args {
            [o, hi, m] => {
                let m = quant_bound(m)?;
                let f = if intrinsic == I::FrameStep {
                    quant::frame_step
                } else {
                    snapped::sg_bins
                };
                lanewise2(o, hi, &|x, y| match (x, y) {
                    (Scalar::F32(o), Scalar::F32(hi)) => Ok(Scalar::F32(f(o, hi, m))),
                    _ => Err("expects f32 lanes".into()),
                })
            }
            _ => Err(format!("`{name}` needs three operands")),
        },
        I::QuantLo | I::QuantHi | I::SgCodeUp | I::SgCodeDown => match args {
            [v, o, s, m] => {
                let m = quant_bound(m)?;
                let f = match intrinsic {
                    I::QuantLo => quant::quant_lo,
                    I::QuantHi => quant::quant_hi,
                    I::SgCodeUp => snapped::sg_code_up,
                    _ => snapped::sg_code_down,
                };
                let (v, o, s) = (lanes(v)?, lanes(o)?, lanes(s)?);
                if v.len() != o.len() || o.len() != s.len() {
                    return Err(format!("`{name}` needs vectors of one length"));
                }
                v.iter()
                    .zip(o)
                    .zip(s)
                    .map(|((v, o), s)| match (v, o, s) {
                        (Val::F32(v), Val::F32(o), Val::F32(s)) => {
                            Ok(Val::Int(f(*v, *o, *s, m) as i128, IntTy::U32))
                        }
                        _ => Err("expects f32 lanes".to_string()),
                    })
                    .collect::<Result<_, _>>()
                    .map(Val::Vector)
            }
            _ => Err(format!("`{name}` needs four operands")),
        },
        I::Popcount | I::Clz | I::Ctz => lanewise1(one()?, &|x| match x {
            Scalar::Int(v, t) => {
                let w = t.bits();
                let raw = (v as u128) & ((1u128 << w) - 1);
                let n = match intrinsic {
                    I::Popcount => raw.count_ones(),
                    I::Clz => raw.leading_zeros() - (128 - w),
                    _ => raw.trailing_zeros().min(w),
                };
                Ok(Scalar::Int(n as i128, t))
            }
            _ => Err("expects integers".into()),
        }),
        I::IsNan => lanewise1(one()?, &|x| match x {
            Scalar::F32(v) => Ok(Scalar::Bool(v.is_nan())),
            Scalar::F64(v) => Ok(Scalar::Bool(v.is_nan())),
            _ => Err("expects floats".into()),
        }),
        I::Dot => {
            let (a, b) = two()?;
            dot(a, b)
        }
        I::Length => {
            let a = one()?;
            float1(&dot(a, a)?, f32::sqrt, f64::sqrt)
        }
        I::Normalize => {
            let a = one()?;
            let len = float1(&dot(a, a)?, f32::sqrt, f64::sqrt)?;
            let l = lanes(a)?;
            let out: Result<Vec<Val>, String> = l
                .iter()
                .map(|x| {
                    lanewise2(x, &len, &|p, q| {
                        crate::tree::scalar::binary(crate::tree::Op::Div, p, q)
                            .ok_or_else(|| "bad operands".into())
                    })
                })
                .collect();
            Ok(Val::Vector(out?))
        }
        I::Cross => {
            let (a, b) = two()?;
            let (x, y) = (lanes(a)?, lanes(b)?);
            if x.len() != 3 || y.len() != 3 {
                return Err("`cross` needs 3-lane vectors".into());
            }
            let c = |i: usize, j: usize| -> R { sub(&mul(&x[i], &y[j])?, &mul(&x[j], &y[i])?) };
            Ok(Val::Vector(vec![c(1, 2)?, c(2, 0)?, c(0, 1)?]))
        }
        I::Hmin => fold_lanes(one()?, &|a, b| min_max(a, b, false)),
        I::Hmax => fold_lanes(one()?, &|a, b| min_max(a, b, true)),
        I::Hsum => fold_lanes(one()?, &add),
        I::Sort => {
            let Val::Array(a) = one()? else {
                return Err("`sort` takes an array".into());
            };
            let mut items = (**a).clone();
            for (i, j) in crate::tree::sort::network(items.len()) {
                if less(&items[j], &items[i])? {
                    items.swap(i, j);
                }
            }
            Ok(Val::Array(Rc::new(items)))
        }
        I::Len => match (one()?, scalar_type(m, result)) {
            (Val::Array(a) | Val::Set(a), Type::Int(t)) => {
                Ok(Val::Int(t.wrap(a.len() as i128), *t))
            }
            _ => Err("`len` takes an array or a set and gives an integer".into()),
        },
        I::SetInsert => match two()? {
            (Val::Set(s), v) => {
                let mut items = (**s).clone();
                if let Err(pos) = items.binary_search_by(|x| x.total_cmp(v)) {
                    items.insert(pos, v.clone());
                }
                Ok(Val::Set(Rc::new(items)))
            }
            _ => Err("expects a set".into()),
        },
    }
}

/// The bound `m` of the quantization builtins, converted to `u32` as `as u32` does.
fn quant_bound(m: &Val) -> Result<u32, String> {
    match m {
        Val::Int(v, _) => Ok(*v as u32),
        _ => Err("the code bound must be an integer".into()),
    }
}

/// `a * b + c` rounded once, lane-wise.
fn fma3(a: &Val, b: &Val, c: &Val) -> R {
    match (a, b, c) {
        (Val::Vector(x), Val::Vector(y), Val::Vector(z))
            if x.len() == y.len() && y.len() == z.len() =>
        {
            x.iter()
                .zip(y)
                .zip(z)
                .map(|((p, q), r)| fma3(p, q, r))
                .collect::<Result<_, _>>()
                .map(Val::Vector)
        }
        (Val::F32(p), Val::F32(q), Val::F32(r)) => Ok(Val::F32(p.mul_add(*q, *r))),
        (Val::F64(p), Val::F64(q), Val::F64(r)) => Ok(Val::F64(p.mul_add(*q, *r))),
        _ => Err("`fma` expects floats of one type".into()),
    }
}
