//! `scion-bench`: whole-run throughput of closest-hit tracers against peers, by the paper's method
//! (§9, architecture §7), and the helpers the `peers` and `compile` benchmarks share.
//!
//! Input: a scene, a ray kind and count, and a list of [`Contender`]s (each a way to trace the
//! rays: Scion's generated code through a backend, the runtime's Rust reference, a peer library).
//! Output: one [`Outcome`] per contender: the trimmed-mean time, Mrays/s, the ratio to the first
//! contender (the peer every other row is compared with), and how many hits agree with the first
//! contender's bit for bit.
//!
//! Runs are interleaved: one warm-up round, then nine rounds in which every contender traces once,
//! so a burst of noise on the shared machine hits every row alike; per contender, the two fastest
//! and two slowest of the nine are dropped and the other five averaged
//! ([`scion_runtime::timing::trimmed_mean`]).

pub mod foreign_tree;
pub mod pbrt_kernel;
pub mod records;

use scion_runtime::bvh::{build_sah_binned, LogicalTree, SahOptions};
use scion_runtime::geom::{Hit, Ray, Triangle};
use scion_runtime::query::{primary_rays_n, secondary_rays};
use scion_runtime::scene::load_obj;
use scion_runtime::timing::{trimmed_mean, TimingPlan};
use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

/// Which rays to trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// Camera rays framing the scene (coherent).
    Primary,
    /// Random rays from points inside the scene's box (incoherent).
    Secondary,
}

impl RayKind {
    /// `primary` or `secondary`.
    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Secondary => "secondary",
        }
    }

    /// The kind named `s`.
    pub fn parse(s: &str) -> Result<RayKind, String> {
        match s {
            "primary" => Ok(RayKind::Primary),
            "secondary" => Ok(RayKind::Secondary),
            _ => Err(format!(
                "unknown ray kind `{s}` (expected primary or secondary)"
            )),
        }
    }
}

/// A scene, its logical tree (binned SAH, leaves of at most 15, as `scion trace` builds it) and
/// the rays to trace.
pub struct Workload {
    /// The scene's file stem.
    pub scene: String,
    /// The scene's triangles.
    pub triangles: Vec<Triangle>,
    /// The logical tree over them.
    pub tree: LogicalTree,
    /// The rays.
    pub rays: Vec<Ray>,
    /// Which rays they are.
    pub kind: RayKind,
    /// The tree of blocks of four triangles the `Triangle4` layouts traverse, when another
    /// builder than Scion's block SAH tree makes it (`--tree`); `None`: `sah_block_tree`.
    pub blocks: Option<LogicalTree<scion_runtime::triangle4::Triangle4>>,
}

impl Workload {
    /// Loads `scene`, builds its tree and makes `n` rays of `kind` with `seed`, exactly as
    /// `scion trace --rays KIND --n N --seed SEED` does.
    pub fn load(scene: &Path, kind: RayKind, n: usize, seed: u64) -> Result<Workload, String> {
        let loaded = load_obj(scene).map_err(|e| format!("{}: {e}", scene.display()))?;
        if loaded.triangles.is_empty() {
            return Err(format!("{}: the scene has no triangles", scene.display()));
        }
        let tree = build_sah_binned(&loaded.triangles, &SahOptions::default());
        let b = loaded.bounds();
        let rays = match kind {
            // The rays `scion trace` and `scion explore` make for the same size and seed.
            RayKind::Primary => primary_rays_n(b, n as u64, seed)
                .ok_or_else(|| format!("{n} primary rays: none, or too many"))?,
            RayKind::Secondary => secondary_rays(b, n, seed),
        };
        let stem = scene.file_stem().map_or_else(
            || scene.display().to_string(),
            |s| s.to_string_lossy().into(),
        );
        Ok(Workload {
            scene: stem,
            triangles: loaded.triangles,
            tree,
            rays,
            kind,
            blocks: None,
        })
    }
}

/// The tracing closure of a contender: rays in, one hit per ray out.
pub type TraceFn<'a> = Box<dyn FnMut(&[Ray]) -> Result<Vec<Hit>, String> + 'a>;

/// One way to trace the workload's rays.
pub struct Contender<'a> {
    /// The row's name (`reference`, `llvm-O3 pbrt`, `obvhs cwbvh`, ...).
    pub name: String,
    /// Bytes of the structure it traverses, when known.
    pub bytes: Option<usize>,
    /// Time it took to build or pack its structure (not part of the traced time).
    pub setup: Duration,
    /// Traces only the first `subset` rays (a slow contender, such as an interpreter); its
    /// throughput is computed on those.
    pub subset: Option<usize>,
    /// Traces rays.
    pub trace: TraceFn<'a>,
}

/// The measurement of one contender.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The contender's name.
    pub name: String,
    /// Structure bytes, when known.
    pub bytes: Option<usize>,
    /// Build or pack time.
    pub setup: Duration,
    /// Rays traced per run.
    pub rays: usize,
    /// Every timed run.
    pub raw: Vec<Duration>,
    /// Trimmed mean of the runs.
    pub mean: Duration,
    /// Hits equal (bit for bit: `t` and primitive) to the first contender's, among `rays`.
    pub agree: usize,
    /// Hits naming the same primitive as the first contender's (a miss names none), among
    /// `rays`: peers with another triangle test differ in the last bits of `t`, not in this.
    pub same_prim: usize,
}

impl Outcome {
    /// Millions of rays per second.
    pub fn mrays(&self) -> f64 {
        self.rays as f64 / self.mean.as_secs_f64().max(f64::MIN_POSITIVE) / 1e6
    }
}

/// Measures every contender on `rays` by `plan`, interleaved (see the module comment). The first
/// contender is the peer the others' hits are compared with. `progress` gets one line per round.
pub fn race(
    rays: &[Ray],
    contenders: &mut [Contender<'_>],
    plan: &TimingPlan,
    mut progress: impl FnMut(&str),
) -> Result<Vec<Outcome>, String> {
    // The first trace of each gives the hits to compare; it also warms caches and code.
    let mut firsts: Vec<Vec<Hit>> = Vec::with_capacity(contenders.len());
    for c in contenders.iter_mut() {
        let part = &rays[..c.subset.unwrap_or(rays.len()).min(rays.len())];
        let hits = (c.trace)(part).map_err(|e| format!("{}: {e}", c.name))?;
        if hits.len() != part.len() {
            return Err(format!(
                "{}: {} hits for {} rays",
                c.name,
                hits.len(),
                part.len()
            ));
        }
        firsts.push(hits);
    }
    for round in 0..plan.warmup.saturating_sub(1) {
        progress(&format!("warm-up round {}", round + 2));
        for c in contenders.iter_mut() {
            let part = &rays[..c.subset.unwrap_or(rays.len()).min(rays.len())];
            (c.trace)(part).map_err(|e| format!("{}: {e}", c.name))?;
        }
    }
    let runs = plan.runs.max(1);
    let mut raw: Vec<Vec<Duration>> = vec![Vec::with_capacity(runs); contenders.len()];
    for round in 0..runs {
        progress(&format!("round {} of {runs}", round + 1));
        for (k, c) in contenders.iter_mut().enumerate() {
            let part = &rays[..c.subset.unwrap_or(rays.len()).min(rays.len())];
            let start = Instant::now();
            let hits = (c.trace)(part).map_err(|e| format!("{}: {e}", c.name))?;
            raw[k].push(start.elapsed());
            std::hint::black_box(hits);
        }
    }
    let peer = &firsts[0];
    Ok(contenders
        .iter()
        .zip(raw)
        .zip(&firsts)
        .map(|((c, raw), hits)| Outcome {
            name: c.name.clone(),
            bytes: c.bytes,
            setup: c.setup,
            rays: hits.len(),
            mean: trimmed_mean(&raw, plan.drop_low, plan.drop_high),
            raw,
            agree: agreeing(peer, hits),
            same_prim: peer
                .iter()
                .zip(hits)
                .filter(|(x, y)| x.prim == y.prim)
                .count(),
        })
        .collect())
}

/// Hits of `b` equal to `a`'s at the same index, bit for bit.
pub fn agreeing(a: &[Hit], b: &[Hit]) -> usize {
    a.iter()
        .zip(b)
        .filter(|(x, y)| x.t.to_bits() == y.t.to_bits() && x.prim == y.prim)
        .count()
}

/// The outcomes as a markdown table: one row per contender, with the ratio of its throughput to
/// the first row's.
pub fn table(w: &Workload, threads: usize, outcomes: &[Outcome]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Scene {} ({} triangles), {} {} rays, {} thread(s).\n",
        w.scene,
        w.triangles.len(),
        w.rays.len(),
        w.kind.name(),
        threads
    );
    s.push_str(&outcome_rows(outcomes, "same primitive"));
    s
}

/// The outcomes as markdown table rows under a header: one row per contender, with the ratio
/// of its throughput to the first row's, and how many of its hits name the same primitive as
/// the first row's (the column called `same`).
pub fn outcome_rows(outcomes: &[Outcome], same: &str) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| tracer | Mrays/s | / {peer} | setup s | MB | hits equal to {peer} | {same} |",
        peer = outcomes.first().map_or("peer", |o| o.name.as_str()),
    );
    let _ = writeln!(s, "|---|---:|---:|---:|---:|---:|---:|");
    let base = outcomes.first().map_or(1.0, Outcome::mrays);
    for o in outcomes {
        let mb = o
            .bytes
            .map_or_else(|| "-".to_string(), |b| format!("{:.2}", b as f64 / 1e6));
        let _ = writeln!(
            s,
            "| {} | {:.3} | {:.2} | {:.3} | {} | {} / {} | {} |",
            o.name,
            o.mrays(),
            o.mrays() / base,
            o.setup.as_secs_f64(),
            mb,
            o.agree,
            o.rays,
            o.same_prim
        );
    }
    s
}

/// The rows of a peers file (`scion_runtime::timing::PEER_FIELDS`, no header) for the peer
/// libraries among `outcomes` (every row but Scion's own, `llvm-O3 ...`, `cranelift ...`,
/// `interpreter ...`, and the `reference`), each anchored to `anchor` measured in the same run;
/// `n` is the size asked for (the context's).
pub fn peer_csv_rows(
    w: &Workload,
    n: usize,
    threads: usize,
    outcomes: &[Outcome],
    anchor: &str,
) -> Result<String, String> {
    let ns = |o: &Outcome| o.mean.as_secs_f64() * 1e9 / o.rays.max(1) as f64;
    let a = outcomes
        .iter()
        .find(|o| o.name == anchor)
        .ok_or_else(|| format!("--peer-csv: no `{anchor}` row in this run to anchor the peers"))?;
    let ours = |name: &str| {
        name == "reference"
            || ["llvm-O", "cranelift ", "interpreter"]
                .iter()
                .any(|p| name.starts_with(p))
    };
    let mut s = String::new();
    for o in outcomes.iter().filter(|o| !ours(&o.name)) {
        let _ = writeln!(
            s,
            "{},closest-hit,{},{n},{threads},{},{},{},{:.4},{anchor},{:.4}",
            w.scene,
            w.kind.name(),
            o.name,
            o.bytes.map_or_else(String::new, |b| b.to_string()),
            w.triangles.len(),
            ns(o),
            ns(a),
        );
    }
    Ok(s)
}

/// The outcomes as tab-separated lines (no header): scene, triangles, ray kind, rays, threads,
/// tracer, Mrays/s, ratio to the first row, setup seconds, bytes (`-` when unknown), hits equal
/// to the first row's, hits naming the same primitive. [`TSV_HEADER`] names the columns.
pub fn tsv_rows(w: &Workload, threads: usize, outcomes: &[Outcome]) -> String {
    let base = outcomes.first().map_or(1.0, Outcome::mrays);
    let mut s = String::new();
    for o in outcomes {
        let _ = writeln!(
            s,
            "{}\t{}\t{}\t{}\t{}\t{}\t{:.4}\t{:.4}\t{:.4}\t{}\t{}\t{}",
            w.scene,
            w.triangles.len(),
            w.kind.name(),
            o.rays,
            threads,
            o.name,
            o.mrays(),
            o.mrays() / base,
            o.setup.as_secs_f64(),
            o.bytes.map_or_else(|| "-".to_string(), |b| b.to_string()),
            o.agree,
            o.same_prim
        );
    }
    s
}

/// The columns of [`tsv_rows`].
pub const TSV_HEADER: &str =
    "scene\ttriangles\trays\tn\tthreads\ttracer\tmrays\tratio\tsetup_s\tbytes\tagree\tsame_prim";

/// Walks a harness-less benchmark's command line: `each` gets every flag in order (`cargo
/// bench`'s own `--bench` left out) and a function that takes the flag's value.
pub fn parse_flags(
    mut each: impl FnMut(&str, &mut dyn FnMut() -> Result<String, String>) -> Result<(), String>,
) -> Result<(), String> {
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        if flag == "--bench" {
            continue;
        }
        let mut value = || {
            it.next()
                .filter(|v| v != "--bench")
                .ok_or(format!("{flag} needs a value"))
        };
        each(&flag, &mut value)?;
    }
    Ok(())
}

/// Flag `flag`'s value `s` as a number.
pub fn flag_number(flag: &str, s: &str) -> Result<u64, String> {
    s.parse::<u64>()
        .map_err(|_| format!("{flag}: `{s}` is not a number"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use scion_runtime::geom::Vec3;

    fn ray(x: f32) -> Ray {
        Ray {
            origin: Vec3 { x, y: 0.0, z: 0.0 },
            dir: Vec3 {
                x: 0.0,
                y: 0.0,
                z: 1.0,
            },
            tmin: 0.0,
            tmax: f32::INFINITY,
        }
    }

    #[test]
    fn race_interleaves_and_compares_with_the_first_contender() {
        let rays: Vec<Ray> = (0..10).map(|i| ray(i as f32)).collect();
        let calls = std::cell::Cell::new(0usize);
        let exact = |r: &[Ray]| -> Result<Vec<Hit>, String> {
            Ok(r.iter()
                .map(|q| Hit {
                    t: q.origin.x,
                    prim: 1,
                })
                .collect())
        };
        let mut contenders = vec![
            Contender {
                name: "peer".into(),
                bytes: Some(100),
                setup: Duration::ZERO,
                subset: None,
                trace: Box::new(exact),
            },
            Contender {
                name: "off-by-one-on-odd".into(),
                bytes: None,
                setup: Duration::ZERO,
                subset: Some(4),
                trace: Box::new(|r: &[Ray]| {
                    calls.set(calls.get() + 1);
                    Ok(r.iter()
                        .enumerate()
                        .map(|(i, q)| Hit {
                            t: q.origin.x,
                            prim: 1 + (i % 2) as u32,
                        })
                        .collect())
                }),
            },
        ];
        let plan = TimingPlan::PAPER;
        let out = race(&rays, &mut contenders, &plan, |_| {}).unwrap();
        drop(contenders);
        // One first trace, no extra warm-up round (the first trace is the warm-up), 9 runs.
        assert_eq!(calls.get(), 10);
        assert_eq!(out[0].agree, 10);
        assert_eq!(out[0].rays, 10);
        assert_eq!(out[1].rays, 4);
        assert_eq!(out[1].agree, 2);
        assert_eq!(out[1].same_prim, 2);
        assert_eq!(out[1].raw.len(), 9);
    }

    #[test]
    fn a_failing_contender_names_itself() {
        let rays = vec![ray(0.0)];
        let mut contenders = vec![Contender {
            name: "broken".into(),
            bytes: None,
            setup: Duration::ZERO,
            subset: None,
            trace: Box::new(|_: &[Ray]| Err("stack overflow".to_string())),
        }];
        let e = race(&rays, &mut contenders, &TimingPlan::PAPER, |_| {}).unwrap_err();
        assert_eq!(e, "broken: stack overflow");
    }

    #[test]
    fn ray_kinds_parse() {
        assert_eq!(RayKind::parse("primary"), Ok(RayKind::Primary));
        assert!(RayKind::parse("shadow")
            .unwrap_err()
            .contains("primary or secondary"));
    }
}
