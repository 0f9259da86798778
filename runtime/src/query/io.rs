//! Binary query and result files (documented in docs/formats.md): rays and hits <-> bytes.
//!
//! - Rays file: one 32-byte record per ray, eight little-endian `f32`:
//!   `ox oy oz dx dy dz tmin tmax`.
//! - Hits file: one 8-byte record per ray, a little-endian `f32` `t` (`+inf` on a miss) then a
//!   little-endian `u32` primitive id (`0xFFFFFFFF` on a miss).
//!
//! No header: the record count is the file size divided by the record size, and a size that is
//! not a multiple is an error naming the file. Values are not checked (NaN rays are allowed,
//! as hard cases).

use std::fmt;
use std::path::{Path, PathBuf};

use crate::geom::{Hit, Ray, Vec3};

/// Bytes per ray record.
pub const RAY_RECORD: usize = 32;
/// Bytes per hit record.
pub const HIT_RECORD: usize = 8;

/// Why a query or result file could not be read or written.
#[derive(Debug)]
pub enum QueryFileError {
    /// The file could not be opened, read or written.
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file's size is not a whole number of records.
    BadSize {
        /// The file (or `<memory>`).
        path: PathBuf,
        /// Its size in bytes.
        size: usize,
        /// What it should hold.
        what: &'static str,
        /// The record size.
        record: usize,
    },
}

impl fmt::Display for QueryFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            QueryFileError::Io { path, source } => write!(f, "{}: {source}", path.display()),
            QueryFileError::BadSize {
                path,
                size,
                what,
                record,
            } => write!(
                f,
                "{}: {size} bytes is not a whole number of {what} records ({record} bytes each; \
                 {} trailing bytes)",
                path.display(),
                size % record
            ),
        }
    }
}

impl std::error::Error for QueryFileError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            QueryFileError::Io { source, .. } => Some(source),
            QueryFileError::BadSize { .. } => None,
        }
    }
}

fn f32_at(b: &[u8], i: usize) -> f32 {
    f32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

fn check_size(
    path: &Path,
    size: usize,
    what: &'static str,
    record: usize,
) -> Result<(), QueryFileError> {
    if size % record != 0 {
        return Err(QueryFileError::BadSize {
            path: path.to_path_buf(),
            size,
            what,
            record,
        });
    }
    Ok(())
}

/// The bytes of a rays file.
pub fn rays_to_bytes(rays: &[Ray]) -> Vec<u8> {
    let mut out = Vec::with_capacity(rays.len() * RAY_RECORD);
    for r in rays {
        for x in [
            r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, r.tmin, r.tmax,
        ] {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    out
}

/// Rays from the bytes of a rays file; `path` names the source in errors.
pub fn rays_from_bytes(path: &Path, bytes: &[u8]) -> Result<Vec<Ray>, QueryFileError> {
    check_size(path, bytes.len(), "ray", RAY_RECORD)?;
    Ok(bytes
        .chunks_exact(RAY_RECORD)
        .map(|b| Ray {
            origin: Vec3::new(f32_at(b, 0), f32_at(b, 4), f32_at(b, 8)),
            dir: Vec3::new(f32_at(b, 12), f32_at(b, 16), f32_at(b, 20)),
            tmin: f32_at(b, 24),
            tmax: f32_at(b, 28),
        })
        .collect())
}

/// The bytes of a hits file.
pub fn hits_to_bytes(hits: &[Hit]) -> Vec<u8> {
    let mut out = Vec::with_capacity(hits.len() * HIT_RECORD);
    for h in hits {
        out.extend_from_slice(&h.t.to_le_bytes());
        out.extend_from_slice(&h.prim.to_le_bytes());
    }
    out
}

/// The checksum of a list of hits that `scion trace`, the C library
/// (`scion_hits_checksum`) and the C++ example print: 64-bit FNV-1a over the bytes of the hits
/// file ([`hits_to_bytes`]: per hit the little-endian `f32` bits of `t`, then the `u32`
/// primitive id), so two lists have the same checksum when they are bit-identical (with
/// overwhelming probability only then).
pub fn hits_checksum(hits: &[Hit]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for hit in hits {
        for b in hit
            .t
            .to_bits()
            .to_le_bytes()
            .into_iter()
            .chain(hit.prim.to_le_bytes())
        {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    h
}

/// Hits from the bytes of a hits file; `path` names the source in errors.
pub fn hits_from_bytes(path: &Path, bytes: &[u8]) -> Result<Vec<Hit>, QueryFileError> {
    check_size(path, bytes.len(), "hit", HIT_RECORD)?;
    Ok(bytes
        .chunks_exact(HIT_RECORD)
        .map(|b| Hit {
            t: f32_at(b, 0),
            prim: u32_at(b, 4),
        })
        .collect())
}

fn read(path: &Path) -> Result<Vec<u8>, QueryFileError> {
    std::fs::read(path).map_err(|source| QueryFileError::Io {
        path: path.to_path_buf(),
        source,
    })
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), QueryFileError> {
    write_whole(path, bytes).map_err(|source| QueryFileError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Writes `bytes` to `path` whole or not at all: into a temporary file beside it (hidden, named
/// with this process's id), synced, then renamed over it. An interrupted or failed write leaves
/// the previous file as it was and no truncated file that would still read as valid records.
pub fn write_whole(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let name = path
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{name}.scion-{}.tmp", std::process::id()));
    let written = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

/// Writes a rays file (whole or not at all, [`write_whole`]).
pub fn write_rays(path: impl AsRef<Path>, rays: &[Ray]) -> Result<(), QueryFileError> {
    write(path.as_ref(), &rays_to_bytes(rays))
}

/// Reads a rays file.
pub fn read_rays(path: impl AsRef<Path>) -> Result<Vec<Ray>, QueryFileError> {
    let path = path.as_ref();
    rays_from_bytes(path, &read(path)?)
}

/// Writes a hits file (whole or not at all, [`write_whole`]).
pub fn write_hits(path: impl AsRef<Path>, hits: &[Hit]) -> Result<(), QueryFileError> {
    write(path.as_ref(), &hits_to_bytes(hits))
}

/// Reads a hits file.
pub fn read_hits(path: impl AsRef<Path>) -> Result<Vec<Hit>, QueryFileError> {
    let path = path.as_ref();
    hits_from_bytes(path, &read(path)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksum_is_fnv1a_of_the_hits_file_bytes() {
        // FNV-1a 64 of no bytes is the offset basis.
        assert_eq!(hits_checksum(&[]), 0xcbf2_9ce4_8422_2325);
        let hits = [Hit { t: 1.5, prim: 7 }, Hit::MISS];
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in hits_to_bytes(&hits) {
            h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        }
        assert_eq!(hits_checksum(&hits), h);
        // One bit of one hit changes it.
        let other = [Hit { t: 1.5, prim: 6 }, Hit::MISS];
        assert_ne!(hits_checksum(&hits), hits_checksum(&other));
    }

    #[test]
    fn byte_layout_is_little_endian_records() {
        let r = Ray {
            origin: Vec3::new(1.0, 2.0, 3.0),
            dir: Vec3::new(-0.0, 0.5, f32::NAN),
            tmin: 0.0,
            tmax: f32::INFINITY,
        };
        let b = rays_to_bytes(&[r]);
        assert_eq!(b.len(), 32);
        assert_eq!(&b[0..4], &1.0f32.to_le_bytes());
        assert_eq!(&b[28..32], &f32::INFINITY.to_le_bytes());
        let back = rays_from_bytes(Path::new("m"), &b).unwrap();
        assert_eq!(back[0].dir.x.to_bits(), (-0.0f32).to_bits());
        assert!(back[0].dir.z.is_nan());
        let h = hits_to_bytes(&[Hit::MISS, Hit { t: 2.5, prim: 7 }]);
        assert_eq!(&h[0..8], &[0, 0, 0x80, 0x7f, 0xff, 0xff, 0xff, 0xff]);
        assert_eq!(
            hits_from_bytes(Path::new("m"), &h).unwrap()[1],
            Hit { t: 2.5, prim: 7 }
        );
    }

    #[test]
    fn sizes_are_checked() {
        let e = rays_from_bytes(Path::new("q.rays"), &[0u8; 33]).unwrap_err();
        assert!(e.to_string().starts_with("q.rays: 33 bytes"), "{e}");
        let e = hits_from_bytes(Path::new("q.hits"), &[0u8; 12]).unwrap_err();
        assert!(e.to_string().contains("4 trailing bytes"), "{e}");
        assert!(rays_from_bytes(Path::new("e"), &[]).unwrap().is_empty());
    }
}
