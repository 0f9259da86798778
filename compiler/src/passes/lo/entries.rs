//! `add-entries`: adds the exported C entry points of `--entry` ([`crate::abi::entries`]): the
//! per-query and batch functions, the layout's `sizes`/`build`/`root`, and with a GPU target the
//! kernels. Input and output: `lo`. The driver puts the request (the entry signature it derived
//! from `--entry` and `--layout`) in the pass context as an [`EntryRequest`]; the pass runs last,
//! after the lowering.

use crate::abi::{self, EntrySig, EntryTarget};
use scion_ir::diag::Diagnostic;
use scion_ir::{Module, Pass, PassCx, PassError};

/// What `add-entries` adds: the entries of one algorithm over one layout, for one target.
#[derive(Clone, Debug)]
pub struct EntryRequest {
    /// The C signature (from `--entry` and `--layout`).
    pub sig: EntrySig,
    /// CPU entries, or GPU kernels too.
    pub target: EntryTarget,
}

/// The pass object.
pub struct AddEntries;

impl Pass for AddEntries {
    fn name(&self) -> &'static str {
        "add-entries"
    }

    fn summary(&self) -> &'static str {
        "add the exported C entry points of --entry (needs --entry and --layout)"
    }

    fn run(&mut self, m: &mut Module, cx: &mut PassCx) -> Result<bool, PassError> {
        let Some(req) = cx.ext::<EntryRequest>() else {
            return Err(PassError::Diagnostics(
                Diagnostic::error(
                    "E0910",
                    "`add-entries` needs `--entry NAME` and `--layout NAME`",
                )
                .with_note("scionc derives the entry signature from them")
                .into(),
            ));
        };
        abi::entries::add(m, &req.sig, req.target).map_err(|d| PassError::Diagnostics(d.into()))?;
        Ok(true)
    }
}
