//! `tree.intrinsic` to `lo` scalar ops, lane by lane, with the interpreter's exact evaluation
//! order (`dot` sums the lane products left to right without fusing; `cross` is
//! `a[i]*b[j] - a[j]*b[i]`; `hmin`/`hmax`/`hsum` fold left to right).
//!
//! `min`/`max` are `lo.min`/`lo.max` (IEEE minNum/maxNum). Directed rounding keeps its exact
//! ops (`fadd_rd` is `lo.add_rd`, `fsub_ru(a, b)` is `lo.add_ru(a, -b)`, `fmul_rd` is
//! `lo.mul_rd`): NVPTX has them per instruction, CPU backends expand them
//! (`scion_ir::lo::directed`). `isnan` is `x != x`; `rsqrt` is `1 / sqrt`; `length`
//! is `sqrt(dot(v, v))`; `normalize` divides each lane by the length; `with_axis(v, k, x)`
//! selects `x` into lane `k` (a `k` outside the lanes changes nothing). `insert` into a set is
//! `super::sets`'s; the quantization builtins are [`super::quant`]'s.

use super::{FnLower, R};
use scion_ir::attr::Attr;
use scion_ir::entity::{BlockId, TypeId, ValueId};
use scion_ir::lo::Op as L;
use scion_ir::tree::{CmpPred, Intrinsic};
use scion_ir::OpSpec;

/// Lowers `intrinsic` on operand leaves `ins`, giving leaves of types `tys`.
pub(super) fn lower(
    cx: &mut FnLower<'_>,
    cur: BlockId,
    intrinsic: Intrinsic,
    ins: &[Vec<ValueId>],
    tys: &[TypeId],
) -> R<Vec<ValueId>> {
    use Intrinsic as I;
    let name = intrinsic.name();
    let arg = |i: usize| -> R<Vec<ValueId>> {
        ins.get(i)
            .cloned()
            .ok_or((format!("`{name}` is missing an operand"), None))
    };
    let lanewise1 = |cx: &mut FnLower<'_>, op: L| -> R<Vec<ValueId>> {
        Ok(arg(0)?
            .into_iter()
            .map(|x| {
                let ty = cx.ty_of(x);
                cx.e1(cur, op, &[x], ty)
            })
            .collect())
    };
    // `op` on the two operands' lanes, the second one negated first when `negate`.
    let lanewise2 = |cx: &mut FnLower<'_>, op: L, negate: bool| -> R<Vec<ValueId>> {
        let (a, b) = (arg(0)?, arg(1)?);
        Ok(a.iter()
            .zip(&b)
            .map(|(&x, &y)| {
                let ty = cx.ty_of(x);
                let y = if negate {
                    cx.e1(cur, L::Neg, &[y], ty)
                } else {
                    y
                };
                cx.e1(cur, op, &[x, y], ty)
            })
            .collect())
    };
    Ok(match intrinsic {
        I::FrameOrigin
        | I::FrameStep
        | I::QuantLo
        | I::QuantHi
        | I::SgBins
        | I::SgCodeUp
        | I::SgCodeDown => super::quant::lower(cx, cur, intrinsic, ins)?,
        I::Abs => lanewise1(cx, L::Abs)?,
        I::Sqrt => lanewise1(cx, L::Sqrt)?,
        I::Floor => lanewise1(cx, L::Floor)?,
        I::Ceil => lanewise1(cx, L::Ceil)?,
        I::Trunc => lanewise1(cx, L::Trunc)?,
        I::Popcount => lanewise1(cx, L::Popcount)?,
        I::Clz => lanewise1(cx, L::Clz)?,
        I::Ctz => lanewise1(cx, L::Ctz)?,
        I::Min => lanewise2(cx, L::Min, false)?,
        I::Max => lanewise2(cx, L::Max, false)?,
        I::FaddRd => lanewise2(cx, L::AddRd, false)?,
        I::FaddRu => lanewise2(cx, L::AddRu, false)?,
        I::FsubRd => lanewise2(cx, L::AddRd, true)?,
        I::FsubRu => lanewise2(cx, L::AddRu, true)?,
        I::FmulRd => lanewise2(cx, L::MulRd, false)?,
        I::FmulRu => lanewise2(cx, L::MulRu, false)?,
        I::Fma => {
            let (a, b, c) = (arg(0)?, arg(1)?, arg(2)?);
            (0..a.len())
                .map(|i| {
                    let ty = cx.ty_of(a[i]);
                    cx.e1(cur, L::Fma, &[a[i], b[i], c[i]], ty)
                })
                .collect()
        }
        I::Rsqrt => arg(0)?
            .into_iter()
            .map(|x| {
                let ty = cx.ty_of(x);
                let s = cx.e1(cur, L::Sqrt, &[x], ty);
                let one = float_const(cx, cur, ty, 1.0);
                cx.e1(cur, L::Div, &[one, s], ty)
            })
            .collect(),
        I::IsNan => arg(0)?
            .into_iter()
            .map(|x| cx.cmp(cur, CmpPred::Ne, x, x))
            .collect(),
        I::Dot => vec![dot(cx, cur, &arg(0)?, &arg(1)?)?],
        I::WithAxis => {
            // Lane `i` is `k == i ? x : v[i]`; a `k` outside the lanes changes nothing.
            let (v, k, x) = (arg(0)?, arg(1)?, arg(2)?);
            let (&[k], &[x]) = (k.as_slice(), x.as_slice()) else {
                return Err((
                    "`with_axis` takes one lane index and one element".into(),
                    None,
                ));
            };
            let kt = cx.ty_of(k);
            v.iter()
                .enumerate()
                .map(|(i, &lane)| {
                    let c = cx.int_const(cur, kt, i as i128);
                    let here = cx.cmp(cur, CmpPred::Eq, k, c);
                    let ty = cx.ty_of(lane);
                    cx.e1(cur, L::Select, &[here, x, lane], ty)
                })
                .collect()
        }
        I::Length => {
            let a = arg(0)?;
            let d = dot(cx, cur, &a, &a)?;
            let ty = cx.ty_of(d);
            vec![cx.e1(cur, L::Sqrt, &[d], ty)]
        }
        I::Normalize => {
            let a = arg(0)?;
            let d = dot(cx, cur, &a, &a)?;
            let ty = cx.ty_of(d);
            let len = cx.e1(cur, L::Sqrt, &[d], ty);
            a.iter()
                .map(|&x| cx.e1(cur, L::Div, &[x, len], ty))
                .collect()
        }
        I::Cross => {
            let (a, b) = (arg(0)?, arg(1)?);
            if a.len() != 3 || b.len() != 3 {
                return Err(("`cross` needs 3 lanes".into(), None));
            }
            let ty = cx.ty_of(a[0]);
            let mut c = |i: usize, j: usize| {
                let p = cx.e1(cur, L::Mul, &[a[i], b[j]], ty);
                let q = cx.e1(cur, L::Mul, &[a[j], b[i]], ty);
                cx.e1(cur, L::Sub, &[p, q], ty)
            };
            vec![c(1, 2), c(2, 0), c(0, 1)]
        }
        I::Hmin | I::Hmax | I::Hsum => {
            let op = match intrinsic {
                I::Hmin => L::Min,
                I::Hmax => L::Max,
                _ => L::Add,
            };
            let a = arg(0)?;
            let Some((&first, rest)) = a.split_first() else {
                return Err(("empty vector".into(), None));
            };
            let ty = cx.ty_of(first);
            let mut acc = first;
            for &x in rest {
                acc = cx.e1(cur, op, &[acc, x], ty);
            }
            vec![acc]
        }
        I::Len => {
            let Some(&ty) = tys.first() else {
                return Err(("`len` without a result".into(), None));
            };
            return Err((
                format!(
                    "`len` of an array (type {}) needs a view",
                    cx.dst.types.display(ty)
                ),
                None,
            ));
        }
        I::Sort => return Err(("`sort` is lowered with its array's length".into(), None)),
        I::SetInsert => return Err(("`insert` is lowered with its set's sink".into(), None)),
    })
}

/// `sort` of `n` elements whose leaves are `leaves` (each element the same number of leaves):
/// the network of `scion_ir::tree::sort`, each comparator a lexicographic `<` and one
/// `lo.select` per leaf in each direction.
pub(super) fn sort(
    cx: &mut FnLower<'_>,
    cur: BlockId,
    leaves: &[ValueId],
    n: usize,
) -> R<Vec<ValueId>> {
    if n == 0 || !leaves.len().is_multiple_of(n) {
        return Err(("`sort` of a malformed array".into(), None));
    }
    let w = leaves.len() / n;
    let mut el: Vec<Vec<ValueId>> = leaves.chunks(w).map(<[ValueId]>::to_vec).collect();
    for (i, j) in scion_ir::tree::sort::network(n) {
        // swap = el[j] < el[i], component by component from the last: lt_k = b_k < a_k ||
        // (b_k == a_k && lt_{k+1}).
        let (a, b) = (el[i].clone(), el[j].clone());
        let mut swap: Option<ValueId> = None;
        for k in (0..w).rev() {
            let lt = cx.cmp(cur, CmpPred::Lt, b[k], a[k]);
            swap = Some(match swap {
                None => lt,
                Some(rest) => {
                    let eq = cx.cmp(cur, CmpPred::Eq, b[k], a[k]);
                    let i1 = cx.ty_of(eq);
                    let both = cx.e1(cur, L::And, &[eq, rest], i1);
                    cx.e1(cur, L::Or, &[lt, both], i1)
                }
            });
        }
        let swap = swap.expect("at least one leaf");
        for k in 0..w {
            let ty = cx.ty_of(a[k]);
            el[i][k] = cx.e1(cur, L::Select, &[swap, b[k], a[k]], ty);
            el[j][k] = cx.e1(cur, L::Select, &[swap, a[k], b[k]], ty);
        }
    }
    Ok(el.concat())
}

fn float_const(cx: &mut FnLower<'_>, cur: BlockId, ty: TypeId, v: f64) -> ValueId {
    let o = cx.insert(
        cur,
        OpSpec::new(L::Const)
            .results(&[ty])
            .attr("value", Attr::float(v)),
    );
    cx.dst.ops[o].results[0]
}

fn dot(cx: &mut FnLower<'_>, cur: BlockId, a: &[ValueId], b: &[ValueId]) -> R<ValueId> {
    if a.is_empty() || a.len() != b.len() {
        return Err(("`dot` needs two vectors of one length".into(), None));
    }
    let ty = cx.ty_of(a[0]);
    let mut acc = cx.e1(cur, L::Mul, &[a[0], b[0]], ty);
    for i in 1..a.len() {
        let p = cx.e1(cur, L::Mul, &[a[i], b[i]], ty);
        acc = cx.e1(cur, L::Add, &[acc, p], ty);
    }
    Ok(acc)
}
