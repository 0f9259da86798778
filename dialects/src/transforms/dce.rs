//! `dce`: removes operations whose results are all unused and whose removal changes nothing
//! observable (pure ops, and `tree.if`/`tree.match` whose regions only compute and yield), until
//! none is left (level: any → same).
//!
//! ```text
//! %2 = "tree.mul"(%0, %1) : (f32, f32) -> f32    // unused: removed
//! "tree.return"(%0) : (f32) -> ()
//! ```
//!
//! Calls, stores, returns and `tree.foreach` stay: they may write through references or leave
//! the function. Uses are counted afresh on each round instead of being maintained.

use crate::module::Module;
use crate::pass::{Pass, PassCx, PassError};
use crate::rewrite;
use crate::walk;

/// The `dce` pass.
#[derive(Default)]
pub struct Dce;

impl Pass for Dce {
    fn name(&self) -> &'static str {
        "dce"
    }

    fn summary(&self) -> &'static str {
        "Remove operations without side effects whose results are unused"
    }

    fn run(&mut self, m: &mut Module, _cx: &mut PassCx) -> Result<bool, PassError> {
        let mut changed = false;
        for f in m.func_order.clone() {
            loop {
                let uses = walk::use_counts(m, f);
                let dead: Vec<_> = walk::func_ops(m, f, walk::Order::Post)
                    .into_iter()
                    .filter(|&op| {
                        let o = &m.ops[op];
                        !o.results.is_empty()
                            && o.results.iter().all(|r| !uses.contains_key(r))
                            && walk::is_removable(m, op)
                    })
                    .collect();
                if dead.is_empty() {
                    break;
                }
                for op in dead {
                    rewrite::erase_op(m, op);
                }
                changed = true;
            }
        }
        Ok(changed)
    }
}
