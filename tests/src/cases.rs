//! What the differential rows run on: scenes (the real ones of the repository's `scenes/` and the
//! runtime's generated hard cases), trees (binned SAH with leaves of 15 and 4, median), ray
//! sets (primary, secondary, axis-parallel with signed zeros, and feature rays that graze
//! vertices and edges or start on surfaces), and [`compare`], the bit-for-bit check.

use scion_runtime::bvh::{
    build_fcpw, build_median, build_sah_binned, FcpwOptions, LogicalTree, SahOptions,
};
use scion_runtime::geom::{Hit, Ray, Vec3};
use scion_runtime::query::{axis_rays, primary_rays, secondary_rays};
use scion_runtime::reference::why_pruned;
use scion_runtime::scene::{load_obj, Scene};

pub use scion_runtime::scene::manifest::{scenes_dir, REAL_SCENES};

/// Loads the real scene `name` (`teapot`, ...) from [`scenes_dir`].
pub fn real_scene(name: &str) -> Result<Scene, String> {
    let dir = scenes_dir().ok_or("no real scenes (set SCION_SCENES)")?;
    let info = scion_runtime::scene::manifest::find(name)
        .ok_or_else(|| format!("`{name}` is not a library scene"))?;
    load_obj(info.path(&dir)).map_err(|e| e.to_string())
}

/// The trees a row can use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TreeKind {
    /// Binned SAH, leaves of up to 15 triangles (the default).
    Sah15,
    /// Binned SAH, leaves of up to 4 triangles.
    Sah4,
    /// Median split, one triangle per leaf (the deepest balanced tree).
    Median,
    /// FCPW's builder (binned surface area over 8 slices of the node's box, leaves of up to 4).
    Fcpw,
}

impl TreeKind {
    /// Builds the tree over `scene`.
    pub fn build(self, scene: &Scene) -> LogicalTree {
        match self {
            TreeKind::Sah15 => build_sah_binned(&scene.triangles, &SahOptions::default()),
            TreeKind::Sah4 => build_sah_binned(
                &scene.triangles,
                &SahOptions {
                    max_leaf: 4,
                    ..SahOptions::default()
                },
            ),
            TreeKind::Median => build_median(&scene.triangles),
            TreeKind::Fcpw => build_fcpw(&scene.triangles, &FcpwOptions::default()),
        }
    }
}

/// The ray sets a row can use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// A pinhole camera's jittered pixels (`n` is rounded down to a square).
    Primary,
    /// Origins in the box, directions on the sphere.
    Secondary,
    /// Origins in the box, directions `±e_k` with `+0.0`/`-0.0` in the other lanes.
    Axis,
    /// Through vertices, edge midpoints and centroids from outside, and from those points
    /// along axes (starting on the surface, zero lanes).
    Features,
}

impl RayKind {
    /// About `n` rays of this kind for `scene`, reproducible from `seed`.
    pub fn rays(self, scene: &Scene, n: usize, seed: u64) -> Vec<Ray> {
        let b = scene.bounds();
        match self {
            RayKind::Primary => {
                let side = (n as f64).sqrt().floor().max(1.0) as u32;
                primary_rays(b, side, side, seed)
            }
            RayKind::Secondary => secondary_rays(b, n, seed),
            RayKind::Axis => axis_rays(b, n, seed),
            RayKind::Features => feature_rays(scene, n),
        }
    }
}

/// The generated hard cases, then those of the real scenes `names` that are present.
pub fn hard_and_real(names: &[&str]) -> Vec<Scene> {
    let mut scenes = scion_runtime::scene::gen::hard_cases();
    scenes.extend(names.iter().filter_map(|n| real_scene(n).ok()));
    scenes
}

/// Rays of every kind for `scene`, reproducible from `seed`: 300 secondary, 256 primary, 100
/// axis-parallel and about 200 feature rays (the set the case-study tests trace).
pub fn mixed_rays(scene: &Scene, seed: u64) -> Vec<Ray> {
    let mut rays = RayKind::Secondary.rays(scene, 300, seed);
    rays.extend(RayKind::Primary.rays(scene, 256, seed));
    rays.extend(RayKind::Axis.rays(scene, 100, seed));
    rays.extend(RayKind::Features.rays(scene, 200, 0));
    rays
}

/// About `n` rays that stress edges and vertices (see [`RayKind::Features`]).
pub fn feature_rays(scene: &Scene, n: usize) -> Vec<Ray> {
    let mut rays = Vec::new();
    let b = scene.bounds();
    if b.is_empty() || scene.is_empty() {
        return rays;
    }
    let c = b.center();
    let e = b.extent();
    let span = e.x.max(e.y).max(e.z).max(f32::MIN_POSITIVE);
    let eye = c + Vec3::new(0.31, 0.57, 1.13) * (span * 2.0);
    // 18 rays per triangle visited.
    let per = 18;
    let step = (scene.len() * per / n.max(per)).max(1);
    for t in scene.triangles.iter().step_by(step) {
        let centroid = (t.p0 + t.p1 + t.p2) * (1.0 / 3.0);
        for target in [
            t.p0,
            t.p1,
            t.p2,
            (t.p0 + t.p1) * 0.5,
            (t.p1 + t.p2) * 0.5,
            centroid,
        ] {
            rays.push(Ray::new(eye, target - eye));
            rays.push(Ray::new(target, Vec3::new(0.0, 0.0, -1.0)));
            rays.push(Ray::new(target, Vec3::new(-0.0, 1.0, 0.0)));
        }
    }
    rays
}

/// Checks that a packing of `packed` bytes is its `records` bytes of node and primitive records
/// plus at most 64 bytes of globals (counts, roots, frames), naming `what` when it is not.
pub fn assert_packed_records(what: &str, packed: usize, records: usize) {
    assert!(
        (records..records + 64).contains(&packed),
        "{what}: {packed} bytes packed for {records} bytes of records"
    );
}

/// What one comparison found.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Agreement {
    /// Rays compared.
    pub rays: usize,
    /// Rays that hit something.
    pub hits: usize,
    /// Rays where brute force found a hit that traversal cannot reach, explained by
    /// `reference::why_pruned` (docs/runtime.md, "Brute force and traversal").
    pub pruned: usize,
}

/// Checks a backend's hits: bit for bit equal to the reference traversal `tree_ref`, and to
/// brute force `brute` except where `why_pruned` proves the brute-force hit lies in a node the
/// traversal must prune (then the backend's hit is never better than brute force's). The
/// error names the row, the ray and both hits.
pub fn compare(
    what: &str,
    tree: &LogicalTree,
    rays: &[Ray],
    got: &[Hit],
    tree_ref: &[Hit],
    brute: &[Hit],
) -> Result<Agreement, String> {
    if got.len() != rays.len() {
        return Err(format!(
            "{what}: {} hits for {} rays",
            got.len(),
            rays.len()
        ));
    }
    let mut a = Agreement {
        rays: rays.len(),
        ..Agreement::default()
    };
    for (i, ((g, r), b)) in got.iter().zip(tree_ref).zip(brute).enumerate() {
        let ray = &rays[i];
        if !g.bit_eq(r) {
            return Err(format!(
                "{what}: ray {i} {ray:?}: got {g:?} (t bits {:#010x}), reference traversal \
                 {r:?} (t bits {:#010x})",
                g.t.to_bits(),
                r.t.to_bits()
            ));
        }
        a.hits += usize::from(g.is_hit());
        if g.bit_eq(b) {
            continue;
        }
        let brute_better = b.is_hit() && (b.t < g.t || (b.t == g.t && b.prim < g.prim));
        if !brute_better || why_pruned(tree, ray, b.prim, b.t).is_none() {
            return Err(format!(
                "{what}: ray {i} {ray:?}: got {g:?}, brute force {b:?}, and pruning does not \
                 explain the difference"
            ));
        }
        a.pruned += 1;
    }
    Ok(a)
}

/// Rays for a strand scene, reproducible from `seed`: 300 secondary, 256 primary and 100
/// axis-parallel rays over its box, and rays from outside aimed at segment ends, midpoints and
/// the edges of their ribbons (a radius off the axis, across the ray), where rounding decides.
pub fn strand_rays(scene: &scion_runtime::scene::strands::StrandScene, seed: u64) -> Vec<Ray> {
    let b = scene.bounds();
    if b.is_empty() {
        return secondary_rays(b, 16, seed);
    }
    let mut rays = secondary_rays(b, 300, seed);
    rays.extend(primary_rays(b, 16, 16, seed));
    rays.extend(axis_rays(b, 100, seed));
    let e = b.extent();
    let span = e.x.max(e.y).max(e.z).max(f32::MIN_POSITIVE);
    let eye = b.center() + Vec3::new(0.31, 0.57, 1.13) * (span * 2.0);
    let step = (scene.segments.len() / 40).max(1);
    for s in scene.segments.iter().step_by(step) {
        let mid = (s.p0 + s.p1) * 0.5;
        for target in [s.p0, s.p1, mid] {
            rays.push(Ray::new(eye, target - eye));
            // Across the ray and the axis: a point a radius (and a hair more) off the axis.
            let d = target - eye;
            let axis = s.p1 - s.p0;
            let side = d.cross(axis);
            let len = side.dot(side).sqrt();
            if len > 0.0 && len.is_finite() {
                for k in [0.999f32, 1.0, 1.001] {
                    let off = side * (s.r0.max(s.r1) * k / len);
                    rays.push(Ray::new(eye, target + off - eye));
                }
            }
        }
    }
    rays
}
