//! The float64 oracle of the collision benchmark (scripts/bench-collide.sh, issue 16): where
//! Scion's pairs and a peer's differ, which side the separating-axis test in `f64` supports
//! (`scion_runtime::reference::collide::triangles_intersect`, the test Scion computes too, so this column says where the peer differs from float64).
//!
//! Usage: collide_f64 A.tris B.tris SCION.pairs PEER.pairs
//! Prints: `N only Scion (f64: k collide), M only the peer (f64: j collide)`.

use scion_bench::records::triangles_from_records;
use scion_runtime::geom::Triangle;
use scion_runtime::reference::collide::triangles_intersect;
use std::collections::{BTreeSet, HashMap};
use std::process::ExitCode;

fn tris(path: &str) -> Result<HashMap<u32, Triangle>, String> {
    let b = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    let t = triangles_from_records(&b).map_err(|e| format!("{path}: {e}"))?;
    Ok(t.into_iter().map(|t| (t.id, t)).collect())
}

fn pairs(path: &str) -> Result<BTreeSet<(u32, u32)>, String> {
    let b = std::fs::read(path).map_err(|e| format!("{path}: {e}"))?;
    let w = |r: &[u8], i: usize| u32::from_le_bytes(r[4 * i..4 * i + 4].try_into().unwrap());
    Ok(b.chunks_exact(8).map(|r| (w(r, 0), w(r, 1))).collect())
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 {
        eprintln!("usage: collide_f64 A.tris B.tris SCION.pairs PEER.pairs");
        return ExitCode::from(2);
    }
    let run = || -> Result<String, String> {
        let (a, b) = (tris(&args[1])?, tris(&args[2])?);
        let (scion, peer) = (pairs(&args[3])?, pairs(&args[4])?);
        let decide = |set: Vec<&(u32, u32)>| -> Result<(usize, usize), String> {
            let mut yes = 0;
            for &(i, j) in &set {
                let (Some(ta), Some(tb)) = (a.get(i), b.get(j)) else {
                    return Err(format!("pair ({i}, {j}) names no triangle of the inputs"));
                };
                yes += usize::from(triangles_intersect(ta, tb));
            }
            Ok((set.len(), yes))
        };
        let (ns, ks) = decide(scion.difference(&peer).collect())?;
        let (np, kp) = decide(peer.difference(&scion).collect())?;
        Ok(format!(
            "{ns} only Scion (f64: {ks} collide), {np} only the peer (f64: {kp} collide)"
        ))
    };
    match run() {
        Ok(line) => {
            println!("{line}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("collide_f64: {e}");
            ExitCode::from(1)
        }
    }
}
