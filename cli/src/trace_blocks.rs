//! `scion trace` (and `scion run`'s closest hit, and the GPU path of `scion trace`) over a
//! layout whose leaves hold blocks of four triangles (the prelude's `Triangle4`, `--layout
//! bvh8-tri4`): the scene's triangles under a binned SAH tree that counts a block as one test
//! (`triangle4::block_sah_options`, leaves of at most [`BLOCK_TREE_MAX_LEAF`] triangles unless
//! `--leaf-size` says otherwise), each leaf's triangles cut into blocks of four
//! (`scion_runtime::triangle4::block_tree`), packed by the layout's generated builder and traced
//! through its batch entry (`scion_host::entries`, the C entries `scionc --entry` exports), and
//! checked bit for bit against the runtime's eight-wide reference over the same blocks
//! (docs/runtime.md: a block answers for its nearest triangle by the tie rule, so those hits are
//! the triangles').

use crate::io::outln;
use crate::{BuilderArg, CliError, TraceArgs};
use scion_host::entries::{Entries, PackedEntries};
use scion_host::jit::Codegen;
use scion_host::library::Resolved;
use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::wide::collapse;
use scion_runtime::bvh::{build_sah_binned, LogicalTree};
use scion_runtime::geom::{Hit, Ray};
use scion_runtime::primitive::Primitive;
use scion_runtime::reference::{closest_hit_wide, closest_hits_wide_stats};
use scion_runtime::scene::Scene;
use scion_runtime::triangle4::{block_sah_options, block_tree, Triangle4, BLOCK_TREE_MAX_LEAF};

/// The primitive type whose layouts this module traces.
pub(crate) const PRIMITIVE: &str = Triangle4::TYPE_NAME;

/// The closest hit over blocks `resolved` names, compiled by `codegen` with its C entries (as
/// `scionc -O3 --entry` compiles it; `--opt-level` and `--no-dsl-opt` do not apply).
pub(crate) fn compile(
    resolved: &Resolved,
    args: &TraceArgs,
    codegen: Codegen,
) -> Result<Entries, CliError> {
    let p = &resolved.program;
    if args.opt_level != 3 || args.no_dsl_opt {
        eprintln!(
            "scion: note: layout `{}` holds blocks of four triangles and is compiled as `scionc \
             -O3 --entry` compiles it; --opt-level and --no-dsl-opt do not apply",
            p.layout
        );
    }
    let entries = crate::trace::compile_entries(p, codegen, args.stack_size)?;
    eprintln!(
        "scion: compiled in {:.3} s",
        entries.compile_time.as_secs_f64()
    );
    Ok(entries)
}

/// The logical tree over the scene's triangles that the blocks are cut from: with `--builder
/// sah` the binned SAH counting a leaf of `n` as `ceil(n / 4)` tests, leaves of at most
/// `--leaf-size` (default [`BLOCK_TREE_MAX_LEAF`], two blocks); the other builders as
/// `scion trace` builds them.
pub(crate) fn build(scene: &Scene, args: &TraceArgs) -> LogicalTree {
    build_with(scene, args.builder, args.leaf_size)
}

/// [`build`] from the builder and `--leaf-size` alone (`scion run`'s arguments too).
pub(crate) fn build_with(scene: &Scene, builder: BuilderArg, leaf: Option<u32>) -> LogicalTree {
    if builder != BuilderArg::Sah {
        return crate::trace::build_with(scene, builder, leaf);
    }
    crate::trace::progress(&format!(
        "building the logical tree of {} triangles (blocks of four)",
        scene.len()
    ));
    let max_leaf = leaf.map_or(BLOCK_TREE_MAX_LEAF, |n| n as usize);
    build_sah_binned(&scene.triangles, &block_sah_options(max_leaf))
}

/// The largest leaf of [`build`]'s SAH tree.
pub(crate) fn leaf_size(args: &TraceArgs) -> usize {
    args.leaf_size.map_or(BLOCK_TREE_MAX_LEAF, |n| n as usize)
}

/// `tree` as a tree over blocks, packed for `entries`.
pub(crate) fn pack(
    entries: &Entries,
    tree: &LogicalTree,
    layout: &str,
) -> Result<(LogicalTree<Triangle4>, PackedEntries), CliError> {
    let blocks = block_tree(tree).map_err(|e| CliError::new(format!("the block tree: {e}")))?;
    let packed = entries
        .pack(&blocks)
        .map_err(|e| CliError::new(format!("layout `{layout}`: {e}")))?;
    Ok((blocks, packed))
}

/// The hits of `rays` through the packed blocks.
pub(crate) fn trace(
    entries: &Entries,
    packed: &PackedEntries,
    rays: &[Ray],
    driver: &BatchDriver,
    layout: &str,
) -> Result<Vec<Hit>, CliError> {
    entries
        .closest_hits(packed, rays, driver)
        .map_err(|f| CliError::new(format!("layout `{layout}`: {f}")))
}

/// The eight-wide reference's hits over the same blocks (what the check compares with).
pub(crate) fn reference(blocks: &LogicalTree<Triangle4>, rays: &[Ray]) -> Vec<Hit> {
    let wide = collapse::<8>(blocks);
    rays.iter()
        .map(|r| closest_hit_wide(&wide, &blocks.primitives, r))
        .collect()
}

/// `--stats`: the eight-wide reference's work over the blocks, per ray.
pub(crate) fn stats(blocks: &LogicalTree<Triangle4>, rays: &[Ray], driver: &BatchDriver) {
    let wide = collapse::<8>(blocks);
    let s = closest_hits_wide_stats(&wide, &blocks.primitives, rays, driver);
    let per = |x: u64| x as f64 / rays.len().max(1) as f64;
    outln!(
        "blocks       {:.2} box tests, {:.2} nodes visited, {:.2} block tests per ray; {} nodes, {} blocks of four ({} triangle slots) (the tree collapsed, eight-wide reference traversal)",
        per(s.boxes_tested),
        per(s.nodes_visited),
        per(s.triangles_tested),
        wide.nodes.len(),
        blocks.primitives.len(),
        blocks.primitives.len() * 4
    );
}
