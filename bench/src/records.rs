//! The triangle files the peers of issue 16 read (FCL's shim, FCPW's script, the float64
//! oracle): 40-byte records, the runtime's `Triangle` as it lies in memory (9 `f32` corners,
//! then the `u32` face id), little-endian.

use scion_runtime::geom::{Triangle, Vec3};

/// `tris` as 40-byte records.
pub fn triangle_records(tris: &[Triangle]) -> Vec<u8> {
    let mut out = Vec::with_capacity(40 * tris.len());
    for t in tris {
        for p in [t.p0, t.p1, t.p2] {
            for x in p.to_array() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        out.extend_from_slice(&t.id.to_le_bytes());
    }
    out
}

/// The triangles of 40-byte records; `Err` when `bytes` is not whole records.
pub fn triangles_from_records(bytes: &[u8]) -> Result<Vec<Triangle>, String> {
    if bytes.len() % 40 != 0 {
        return Err(format!(
            "{} bytes are not whole 40-byte triangles",
            bytes.len()
        ));
    }
    let f = |r: &[u8], i: usize| f32::from_le_bytes(r[4 * i..4 * i + 4].try_into().unwrap());
    Ok(bytes
        .chunks_exact(40)
        .map(|r| {
            let p = |k: usize| Vec3::new(f(r, 3 * k), f(r, 3 * k + 1), f(r, 3 * k + 2));
            let id = u32::from_le_bytes(r[36..40].try_into().unwrap());
            Triangle::new(p(0), p(1), p(2), id)
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_round_trip() {
        let t = Triangle::new(
            Vec3::new(1.0, -2.0, 3.5),
            Vec3::new(0.0, 0.5, 9.0),
            Vec3::new(-1.0, 7.0, 2.0),
            42,
        );
        let b = triangle_records(&[t, t]);
        assert_eq!(b.len(), 80);
        assert_eq!(triangles_from_records(&b).unwrap(), vec![t, t]);
        assert!(triangles_from_records(&b[..79]).is_err());
    }
}
