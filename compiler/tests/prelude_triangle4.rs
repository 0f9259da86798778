//! The prelude's `hit_block` (four triangles stored lane by lane, the nearest by the tie rule) run by
//! the `tree` interpreter equals the runtime's mirror, `scion_runtime::reference::prelude::hit_block`,
//! bit for bit: on random blocks and rays and on the hard cases (lanes tied at one distance,
//! the padding lanes of a short block, rays parallel to a triangle, hits at `tmin` and `tmax`,
//! zero-area triangles, a negative `tmin`, all four lanes missing).

use crate::common;

use scion_ir::interp::{AdtVal, Interp, Val};
use scion_ir::types::IntTy;
use scion_runtime::geom::{Ray, Triangle, Vec3};
use scion_runtime::reference::prelude;
use scion_runtime::rng::SplitMix64;
use scion_runtime::Triangle4;
use std::rc::Rc;

const PROBE: &str = "func probe(ray: Ray, b: Triangle4) -> (f32, u32) = hit_block(ray, b)\n";

fn vec3(v: Vec3) -> Val {
    Val::Vector(vec![Val::F32(v.x), Val::F32(v.y), Val::F32(v.z)])
}

fn ray_val(r: &Ray) -> Val {
    Val::Adt(Rc::new(AdtVal {
        ty: "Ray".into(),
        variant: None,
        fields: vec![
            vec3(r.origin),
            vec3(r.dir),
            Val::F32(r.tmin),
            Val::F32(r.tmax),
        ],
    }))
}

fn block_val(b: &Triangle4) -> Val {
    let floats = |a: &[f32; 4]| Val::Array(Rc::new(a.iter().map(|&x| Val::F32(x)).collect()));
    let ids = Val::Array(Rc::new(
        b.id.iter()
            .map(|&x| Val::Int(i128::from(x), IntTy::U32))
            .collect(),
    ));
    Val::Adt(Rc::new(AdtVal {
        ty: "Triangle4".into(),
        variant: None,
        fields: vec![
            floats(&b.x0),
            floats(&b.y0),
            floats(&b.z0),
            floats(&b.x1),
            floats(&b.y1),
            floats(&b.z1),
            floats(&b.x2),
            floats(&b.y2),
            floats(&b.z2),
            ids,
        ],
    }))
}

/// `hit_block` by the interpreter, as `(t bits, id)`.
fn interpreted(m: &scion_ir::Module, ray: &Ray, b: &Triangle4) -> (u32, u32) {
    let mut interp = Interp::new(m);
    let out = interp
        .call("probe", vec![ray_val(ray), block_val(b)])
        .unwrap_or_else(|e| panic!("probe: {e}"));
    match &out[..] {
        [Val::Tuple(v)] => match &v[..] {
            [Val::F32(t), Val::Int(id, _)] => (t.to_bits(), *id as u32),
            other => panic!("unexpected result {other:?}"),
        },
        other => panic!("unexpected results {other:?}"),
    }
}

fn check(m: &scion_ir::Module, ray: &Ray, b: &Triangle4, what: &str) -> bool {
    let (t, id) = prelude::hit_block(ray, b);
    let got = interpreted(m, ray, b);
    assert_eq!(got, (t.to_bits(), id), "{what}: {ray:?} {b:?}");
    t < f32::INFINITY
}

#[test]
fn hit4_of_the_prelude_is_the_runtimes_bit_for_bit() {
    let m =
        common::tree_module_of(&[("probe.scion", PROBE)], true).unwrap_or_else(|e| panic!("{e}"));
    let mut rng = SplitMix64::new(2026);
    let p = |rng: &mut SplitMix64| {
        Vec3::new(
            rng.next_f32() * 2.0 - 1.0,
            rng.next_f32() * 2.0 - 1.0,
            rng.next_f32() * 0.5 - 0.25,
        )
    };
    let mut hits = 0;
    for round in 0..3000u32 {
        let n = 1 + (round % 4) as usize;
        let mut tris: Vec<Triangle> = (0..n as u32)
            .map(|i| Triangle::new(p(&mut rng), p(&mut rng), p(&mut rng), 40 - 3 * i))
            .collect();
        match round % 7 {
            // Two lanes over one triangle's place: a tie at one distance, the smaller id wins.
            0 if n > 1 => tris[n - 1] = Triangle::new(tris[0].p0, tris[0].p1, tris[0].p2, 1),
            // A zero-area triangle.
            1 => tris[0] = Triangle::new(tris[0].p0, tris[0].p0, tris[0].p1, tris[0].id),
            _ => {}
        }
        let b = Triangle4::new(&tris);
        let origin = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, 2.0);
        let mut ray = Ray::new(
            origin,
            Vec3::new(rng.next_f32() * 0.4 - 0.2, rng.next_f32() * 0.4 - 0.2, -1.0),
        );
        match round % 5 {
            // A ray parallel to the triangles' general plane.
            0 => ray.dir = Vec3::new(1.0, 0.5, 0.0),
            // A window that cuts some hits off.
            1 => (ray.tmin, ray.tmax) = (1.9, 2.05),
            // A negative tmin (hits behind the origin count).
            2 => ray.tmin = -4.0,
            _ => {}
        }
        if check(&m, &ray, &b, &format!("round {round}")) {
            hits += 1;
        }
        // The same ray clipped exactly at the hit: tmax = t misses, tmin just below keeps it.
        let (t, _) = prelude::hit_block(&ray, &b);
        if t.is_finite() {
            let mut at = ray;
            at.tmax = t;
            check(&m, &at, &b, &format!("round {round}, tmax at the hit"));
        }
    }
    assert!(
        hits > 500,
        "only {hits} of 3000 rays hit: the cases test too little"
    );
}
