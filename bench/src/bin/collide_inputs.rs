//! The inputs of the collision benchmark's peers (scripts/bench-collide.sh): a scene's
//! triangles and its copy turned by (60°, 70°, 10°) about the centre of its box (exactly the
//! copy `scion run --algorithm collide` makes, `scion_runtime::reference::collide::rotated`),
//! each as 40-byte records (9 `f32` corners, `u32` face id, little-endian).
//!
//! Usage: collide_inputs SCENE A.tris B.tris [X,Y,Z degrees]

use scion_bench::records::triangle_records;
use scion_runtime::reference::collide::rotated;
use scion_runtime::scene::load_obj;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().collect();
    if !(4..=5).contains(&args.len()) {
        eprintln!("usage: collide_inputs SCENE A.tris B.tris [X,Y,Z]");
        return ExitCode::from(2);
    }
    let angles: Vec<f64> = args
        .get(4)
        .map_or("60,70,10", String::as_str)
        .split(',')
        .filter_map(|a| a.trim().parse().ok())
        .collect();
    let Ok(angles) = <[f64; 3]>::try_from(angles) else {
        eprintln!("collide_inputs: the angles are three numbers, as 60,70,10");
        return ExitCode::from(2);
    };
    let path = scion_runtime::scene::manifest::resolve(std::path::Path::new(&args[1]))
        .unwrap_or_else(|_| args[1].clone().into());
    let scene = match load_obj(&path) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("collide_inputs: {e}");
            return ExitCode::from(1);
        }
    };
    let copy = rotated(&scene.triangles, angles);
    for (file, tris) in [(&args[2], &scene.triangles), (&args[3], &copy)] {
        if let Err(e) = std::fs::write(file, triangle_records(tris)) {
            eprintln!("collide_inputs: cannot write {file}: {e}");
            return ExitCode::from(1);
        }
    }
    ExitCode::SUCCESS
}
