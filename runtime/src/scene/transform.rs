//! Rigid-plus-scale transforms of scenes and instancing: [`Scene`] -> [`Scene`].
//!
//! A [`Transform`] maps a point `p` to `R * (s * p) + t`: first the uniform scale `s`, then the
//! rotation `R`, then the translation `t`. The rotation is given by Euler angles in degrees,
//! applied about the fixed world axes in the order x, then y, then z: `R = Rz(c) * Ry(b) *
//! Rx(a)` for `rotate_deg = [a, b, c]`, each a right-handed (counter-clockwise when the axis
//! points at the viewer) rotation. This is how the paper names rotated scenes
//! (`san-miguel-x35-y22-z47`, §9). The arithmetic is done in `f64` and each coordinate is
//! rounded to `f32` once, so the identity transform returns the input bit for bit.
//!
//! [`instances`] flattens several transformed copies of a scene into one triangle list, the
//! stand-in for the paper's large scenes (e.g. 32 dragons ~ 28 M triangles).

use std::path::Path;

use super::{check_count, Scene, SceneError};
use crate::geom::{Triangle, Vec3};

/// Scale, then rotate (Euler x, y, z in degrees), then translate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    /// Rotation angles in degrees about x, y and z, applied in that order.
    pub rotate_deg: [f64; 3],
    /// Uniform scale factor, applied first.
    pub scale: f64,
    /// Translation, applied last.
    pub translate: [f64; 3],
}

impl Default for Transform {
    fn default() -> Transform {
        Transform::IDENTITY
    }
}

impl Transform {
    /// The identity.
    pub const IDENTITY: Transform = Transform {
        rotate_deg: [0.0; 3],
        scale: 1.0,
        translate: [0.0; 3],
    };

    /// A pure rotation by Euler angles in degrees (x, then y, then z).
    pub fn rotation(x_deg: f64, y_deg: f64, z_deg: f64) -> Transform {
        Transform {
            rotate_deg: [x_deg, y_deg, z_deg],
            ..Transform::IDENTITY
        }
    }

    /// A pure uniform scale.
    pub fn scaling(s: f64) -> Transform {
        Transform {
            scale: s,
            ..Transform::IDENTITY
        }
    }

    /// A pure translation.
    pub fn translation(x: f64, y: f64, z: f64) -> Transform {
        Transform {
            translate: [x, y, z],
            ..Transform::IDENTITY
        }
    }

    /// The rotation matrix `Rz * Ry * Rx` (row-major).
    pub fn rotation_matrix(&self) -> [[f64; 3]; 3] {
        let [a, b, c] = self.rotate_deg.map(f64::to_radians);
        let rx = [
            [1.0, 0.0, 0.0],
            [0.0, a.cos(), -a.sin()],
            [0.0, a.sin(), a.cos()],
        ];
        let ry = [
            [b.cos(), 0.0, b.sin()],
            [0.0, 1.0, 0.0],
            [-b.sin(), 0.0, b.cos()],
        ];
        let rz = [
            [c.cos(), -c.sin(), 0.0],
            [c.sin(), c.cos(), 0.0],
            [0.0, 0.0, 1.0],
        ];
        matmul(rz, matmul(ry, rx))
    }

    /// Applies the transform to one point.
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.apply_with(&self.rotation_matrix(), p)
    }

    fn apply_with(&self, r: &[[f64; 3]; 3], p: Vec3) -> Vec3 {
        if self.rotate_deg == [0.0; 3] {
            // Exact path: no rotation, so no rounding besides scale and translation.
            let f = |v: f32, t: f64| (v as f64 * self.scale + t) as f32;
            return Vec3::new(
                f(p.x, self.translate[0]),
                f(p.y, self.translate[1]),
                f(p.z, self.translate[2]),
            );
        }
        let q = [
            p.x as f64 * self.scale,
            p.y as f64 * self.scale,
            p.z as f64 * self.scale,
        ];
        let row = |i: usize| {
            (r[i][0] * q[0] + r[i][1] * q[1] + r[i][2] * q[2] + self.translate[i]) as f32
        };
        Vec3::new(row(0), row(1), row(2))
    }

    /// Applies the transform to every triangle, keeping ids and the name.
    pub fn apply_scene(&self, scene: &Scene) -> Scene {
        let r = self.rotation_matrix();
        let triangles = scene
            .triangles
            .iter()
            .map(|t| {
                Triangle::new(
                    self.apply_with(&r, t.p0),
                    self.apply_with(&r, t.p1),
                    self.apply_with(&r, t.p2),
                    t.id,
                )
            })
            .collect();
        Scene::new(scene.name.clone(), triangles)
    }
}

fn matmul(a: [[f64; 3]; 3], b: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut m = [[0.0; 3]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, cell) in row.iter_mut().enumerate() {
            *cell = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

/// Flattens one transformed copy of `scene` per transform into one scene.
///
/// Copy `k` of triangle `i` gets id `k * scene.len() + i` (so one copy keeps the ids and the
/// file order). Fails when the total does not fit below `u32::MAX`.
pub fn instances(scene: &Scene, transforms: &[Transform]) -> Result<Scene, SceneError> {
    let n = scene.len();
    let total = n.saturating_mul(transforms.len());
    let name = format!("{}x{}", scene.name, transforms.len());
    check_count(Path::new(&name), total)?;
    let mut triangles = Vec::with_capacity(total);
    for (k, tr) in transforms.iter().enumerate() {
        let r = tr.rotation_matrix();
        for (i, t) in scene.triangles.iter().enumerate() {
            triangles.push(Triangle::new(
                tr.apply_with(&r, t.p0),
                tr.apply_with(&r, t.p1),
                tr.apply_with(&r, t.p2),
                (k * n + i) as u32,
            ));
        }
    }
    Ok(Scene::new(name, triangles))
}

/// `count` copies of `scene` on a grid, each rotated differently, spaced so they do not overlap:
/// a deterministic recipe for large test scenes (e.g. `grid_instances(&dragon, 32)`).
pub fn grid_instances(scene: &Scene, count: usize) -> Result<Scene, SceneError> {
    let b = scene.bounds();
    let size = if b.is_empty() {
        1.0
    } else {
        let e = b.extent();
        (e.x.max(e.y).max(e.z) as f64) * 1.8
    };
    let c = if b.is_empty() {
        Vec3::default()
    } else {
        b.center()
    };
    let side = (count as f64).cbrt().ceil().max(1.0) as usize;
    let transforms: Vec<Transform> = (0..count)
        .map(|k| {
            let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
            let angle = (k as f64) * 37.0;
            // Rotate about the scene's center: move it to the origin first (scale is 1 here).
            let r = Transform::rotation(angle, angle * 0.5, angle * 0.25);
            let m = r.rotation_matrix();
            let rc = [
                m[0][0] * c.x as f64 + m[0][1] * c.y as f64 + m[0][2] * c.z as f64,
                m[1][0] * c.x as f64 + m[1][1] * c.y as f64 + m[1][2] * c.z as f64,
                m[2][0] * c.x as f64 + m[2][1] * c.y as f64 + m[2][2] * c.z as f64,
            ];
            Transform {
                translate: [
                    c.x as f64 - rc[0] + i as f64 * size,
                    c.y as f64 - rc[1] + j as f64 * size,
                    c.z as f64 - rc[2] + l as f64 * size,
                ],
                ..r
            }
        })
        .collect();
    instances(scene, &transforms)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).dot(a - b) < 1e-10
    }

    #[test]
    fn euler_order_is_x_then_y_then_z() {
        // x by 90 sends y to z; then y by 90 sends z to x; then z by 90 sends x to y.
        let t = Transform::rotation(90.0, 90.0, 90.0);
        assert!(close(
            t.apply(Vec3::new(0.0, 1.0, 0.0)),
            Vec3::new(0.0, 1.0, 0.0)
        ));
        // Each axis alone is right-handed.
        let rz = Transform::rotation(0.0, 0.0, 90.0);
        assert!(close(
            rz.apply(Vec3::new(1.0, 0.0, 0.0)),
            Vec3::new(0.0, 1.0, 0.0)
        ));
        let rx = Transform::rotation(90.0, 0.0, 0.0);
        assert!(close(
            rx.apply(Vec3::new(0.0, 1.0, 0.0)),
            Vec3::new(0.0, 0.0, 1.0)
        ));
        let ry = Transform::rotation(0.0, 90.0, 0.0);
        assert!(close(
            ry.apply(Vec3::new(0.0, 0.0, 1.0)),
            Vec3::new(1.0, 0.0, 0.0)
        ));
    }

    #[test]
    fn scale_then_rotate_then_translate() {
        let t = Transform {
            rotate_deg: [0.0, 0.0, 90.0],
            scale: 2.0,
            translate: [10.0, 0.0, 0.0],
        };
        assert!(close(
            t.apply(Vec3::new(1.0, 0.0, 0.0)),
            Vec3::new(10.0, 2.0, 0.0)
        ));
        let p = Vec3::new(0.1, -3.7, 1e-7);
        assert_eq!(Transform::IDENTITY.apply(p), p);
    }

    #[test]
    fn instances_renumber_ids() {
        let s = crate::scene::gen::one_triangle();
        let many = instances(
            &s,
            &[Transform::IDENTITY, Transform::translation(5.0, 0.0, 0.0)],
        )
        .unwrap();
        assert_eq!(many.len(), 2);
        assert_eq!(many.triangles[0], s.triangles[0]);
        assert_eq!(many.triangles[1].id, 1);
        assert_eq!(many.triangles[1].p0.x, s.triangles[0].p0.x + 5.0);
        let g = grid_instances(&s, 5).unwrap();
        assert_eq!(g.len(), 5);
    }
}
