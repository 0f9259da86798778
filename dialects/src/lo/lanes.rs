//! The lane groups of a `lo` function: the runs of scalar ops that `mem-to-lo` marked as the
//! lanes of one four- or eight-lane vector operation (`lane = [group, k, n]`), which a backend
//! with vector registers emits as one vector instruction (`scion-llvm`'s `translate::groups`,
//! `scion-clif`'s `lanes`). The ops stay scalar `lo`: a group a backend does not take is
//! translated op by op, with the same results.

use crate::attr::Attr;
use crate::entity::{BlockId, OpId, ValueId};
use crate::module::Module;
use crate::op::OpKind;
use std::collections::{HashMap, HashSet};

/// The lane marks of `op`: `(group, k, n)`.
pub fn lane_mark(m: &Module, op: OpId) -> Option<(i128, usize, usize)> {
    match m.ops[op].attr("lane")? {
        Attr::List(l) => match l.as_slice() {
            [g, k, n] => Some((g.as_int()?, k.as_int()? as usize, n.as_int()? as usize)),
            _ => None,
        },
        _ => None,
    }
}

/// The groups of the blocks `blocks`, each keyed by its first op: `n` consecutive ops marked
/// as lanes `0 .. n` of one group, of one kind and predicate, one result each of one type, with
/// operands of matching types none of which is another lane's result, and whose first op
/// `accept` takes (the backend's vector kinds and types).
pub fn lane_groups(
    m: &Module,
    blocks: &[BlockId],
    accept: impl Fn(&Module, OpId) -> bool,
) -> HashMap<OpId, Vec<OpId>> {
    let mut out = HashMap::new();
    for &b in blocks {
        let ops = &m.blocks[b].ops;
        let mut i = 0;
        while i < ops.len() {
            let Some((g, 0, n)) = lane_mark(m, ops[i]) else {
                i += 1;
                continue;
            };
            let run = &ops[i..(i + n).min(ops.len())];
            let first = &m.ops[ops[i]];
            if !matches!(first.kind, OpKind::Lo(_)) {
                i += 1;
                continue;
            }
            let results: HashSet<ValueId> = run
                .iter()
                .flat_map(|&o| m.ops[o].results.iter().copied())
                .collect();
            let fits = run.len() == n
                && first.results.len() == 1
                && accept(m, ops[i])
                && run.iter().enumerate().all(|(k, &o)| {
                    let x = &m.ops[o];
                    lane_mark(m, o) == Some((g, k, n))
                        && x.kind == first.kind
                        && x.pred() == first.pred()
                        && x.results.len() == 1
                        && x.operands.len() == first.operands.len()
                        && m.values[x.results[0]].ty == m.values[first.results[0]].ty
                        && x.operands.iter().zip(&first.operands).all(|(&p, &q)| {
                            m.values[p].ty == m.values[q].ty && !results.contains(&p)
                        })
                });
            if fits {
                out.insert(ops[i], run.to_vec());
                i += n;
            } else {
                i += 1;
            }
        }
    }
    out
}
