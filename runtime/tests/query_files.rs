//! Ray and hit files (docs/formats.md): round trips through real files, bit for bit, and
//! clear errors for truncated or missing files.

use crate::common;

use scion_runtime::batch::BatchDriver;
use scion_runtime::bvh::{build_sah_binned, SahOptions};
use scion_runtime::geom::{Hit, Ray, Vec3};
use scion_runtime::query::{
    axis_rays, primary_rays, read_hits, read_rays, secondary_rays, write_hits, write_rays,
    QueryFileError,
};
use scion_runtime::reference::closest_hits_tree;
use scion_runtime::scene::gen;

fn ray_bits(r: &Ray) -> [u32; 8] {
    [
        r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax,
    ]
    .map(f32::to_bits)
}

#[test]
fn rays_and_hits_round_trip_bit_for_bit() {
    let dir = common::scratch("query_files");
    let scene = gen::random_soup(400, 0.1, 3);
    let b = scene.bounds();
    let mut rays = primary_rays(b, 20, 10, 1);
    rays.extend(secondary_rays(b, 300, 2));
    rays.extend(axis_rays(b, 100, 3));
    let mut odd = Ray::new(
        Vec3::new(-0.0, f32::MIN_POSITIVE, 1e-45),
        Vec3::new(f32::NAN, 0.0, -1.0),
    );
    odd.tmin = 0.5;
    odd.tmax = 1e30;
    rays.push(odd);

    let rays_path = dir.join("q.rays");
    write_rays(&rays_path, &rays).unwrap();
    assert_eq!(
        std::fs::metadata(&rays_path).unwrap().len(),
        rays.len() as u64 * 32
    );
    let back = read_rays(&rays_path).unwrap();
    assert_eq!(back.len(), rays.len());
    for (a, b) in rays.iter().zip(&back) {
        assert_eq!(ray_bits(a), ray_bits(b));
    }

    let tree = build_sah_binned(&scene.triangles, &SahOptions::default());
    let hits = closest_hits_tree(&tree, &back, &BatchDriver::sequential());
    assert!(hits.iter().any(|h| h.is_hit()) && hits.iter().any(|h| !h.is_hit()));
    let hits_path = dir.join("q.hits");
    write_hits(&hits_path, &hits).unwrap();
    assert_eq!(
        std::fs::metadata(&hits_path).unwrap().len(),
        hits.len() as u64 * 8
    );
    let hits_back = read_hits(&hits_path).unwrap();
    assert!(hits.iter().zip(&hits_back).all(|(a, b)| a.bit_eq(b)));
    assert!(hits_back
        .iter()
        .filter(|h| !h.is_hit())
        .all(|h| h.bit_eq(&Hit::MISS)));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn truncated_and_missing_files_are_clear_errors() {
    let dir = common::scratch("query_files_bad");
    let p = dir.join("cut.rays");
    std::fs::write(&p, [0u8; 70]).unwrap();
    let e = read_rays(&p).unwrap_err();
    assert!(matches!(e, QueryFileError::BadSize { size: 70, .. }));
    let msg = e.to_string();
    assert!(
        msg.starts_with(&p.display().to_string()) && msg.contains("32 bytes each"),
        "{msg}"
    );

    let p = dir.join("cut.hits");
    std::fs::write(&p, [0u8; 9]).unwrap();
    let msg = read_hits(&p).unwrap_err().to_string();
    assert!(
        msg.contains("9 bytes") && msg.contains("8 bytes each"),
        "{msg}"
    );

    let missing = dir.join("none.rays");
    let e = read_rays(&missing).unwrap_err();
    assert!(matches!(e, QueryFileError::Io { .. }));
    assert!(e.to_string().starts_with(&missing.display().to_string()));
    let _ = std::fs::remove_dir_all(&dir);
}
