//! `scion run --algorithm collide`: a scene against its copy turned by `--rotate` (paper
//! §9.3.3), both built into trees and packed by the layout's generated `build`, the collision
//! entry run on them (`scion_host::collide`), timed by the paper's method, and its pairs
//! compared with the tree-free reference (`scion_runtime::reference::collide`).

use crate::io::outln;
use crate::run::fnv1a;
use crate::trace::{build_for_runs, progress, secs, timed};
use crate::{CliError, RunArgs};
use scion_host::collide::{check_pairs, pairs_to_bytes};
use scion_host::entries::Entries;
use scion_host::library::Resolved;
use scion_runtime::reference::collide::{collide_sweep, rotated};
use scion_runtime::scene::Scene;
use std::time::Duration;

/// Runs the collision of `scene` with its rotated copy.
pub fn run(
    args: &RunArgs,
    resolved: &Resolved,
    entries: &Entries,
    scene: &Scene,
    load_time: Duration,
) -> Result<(), CliError> {
    let p = &resolved.program;
    let [x, y, z] = args.rotate;
    progress(&format!(
        "turning a copy of the scene by ({x}, {y}, {z}) degrees"
    ));
    let copy = Scene::new(
        format!("{} rotated", scene.name),
        rotated(&scene.triangles, args.rotate),
    );
    // The leaf test takes triangle pairs one at a time: no collapse for runs of four.
    let tree_a = build_for_runs(scene, args.builder, args.leaf_size, 1);
    let tree_b = build_for_runs(&copy, args.builder, args.leaf_size, 1);
    progress(&format!("packing both trees into layout `{}`", p.layout));
    let pack = |t| entries.pack(t).map_err(CliError::new);
    let (pa, pb) = (pack(&tree_a)?, pack(&tree_b)?);
    progress("running the collision");
    // The first run learns how many pairs there are; the timed runs get a sink that fits.
    let mut capacity = 1 << 16;
    let (got, timing) = timed(args.runs, || {
        let got = entries
            .collide(&pa, &pb, capacity)
            .map_err(|e| CliError::new(format!("{}: {e}", p.algorithm)))?;
        capacity = capacity.max(got.inserted as usize);
        Ok(got)
    })?;
    progress("checking the pairs against the reference");
    let want = collide_sweep(&scene.triangles, &copy.triangles);
    let check = check_pairs(&got.pairs, &want).map_err(CliError::new)?;
    let bytes = pairs_to_bytes(&got.pairs);

    outln!("scene        {}", args.scene.display());
    outln!("triangles    {} (and as many in the copy)", scene.len());
    outln!(
        "algorithm    {} (collide, {})",
        p.algorithm,
        resolved.tree_type
    );
    outln!(
        "layout       {} ({} + {} bytes packed)",
        p.layout,
        pa.bytes(),
        pb.bytes()
    );
    outln!("rotation     ({x}, {y}, {z}) degrees about the centre of the box");
    outln!("load time    {}", secs(load_time));
    outln!("compile time {}", secs(entries.compile_time));
    outln!("pack time    {}", secs(pa.pack_time + pb.pack_time));
    outln!(
        "time         {} (mean of the middle runs, paper method; one thread)",
        secs(timing.mean)
    );
    outln!("pairs        {}", got.pairs.len());
    outln!("checksum: {:016x}", fnv1a(&bytes));
    outln!("check        {check}");
    if let Some(path) = &args.output {
        crate::io::write_whole(path, &bytes)
            .map_err(|e| CliError::new(format!("cannot write {}: {e}", path.display())))?;
        outln!("output       {} ({} bytes)", path.display(), bytes.len());
    }
    Ok(())
}
