//! The table of query kinds ([`QueryKind`]): per kind, how queries are made or read, how a
//! result record starts, what the reference answer is and when an answer equals it. Used by
//! `scion run` and by the differential table of query kinds (tests/tests/query_kinds.rs) over
//! the entries of `crate::entries`.
//!
//! | kind | query record | result record (starts as) | reference, equality |
//! |---|---|---|---|
//! | closest hit | a `Ray` (32 B) | `(t, id)` 8 B (`(tmax, u32::MAX)`) | the reference traversal of the tree the layout traverses (`crate::hit_reference::Traversed`: binary or wide, decoded boxes); `t` bits and id, or brute force's hit where that reference's rounding pruned it |
//! | any hit | a `Ray` | `u32` (0) | that traversal's closest hit: nonzero iff it hits (or iff brute force hits, likewise) |
//! | closest point | `f32x3` (12 B) | `(d, id, point)` 20 B (`(inf, u32::MAX, 0)`) | float32 brute force, every bit |

use crate::hit_reference::{check_answers, Traversed};
use crate::library::QueryKind;
use scion_runtime::batch::{BatchDriver, BLOCK};
use scion_runtime::geom::{Hit, Ray, Triangle, Vec3};
use scion_runtime::query::{hits_checksum, io::rays_to_bytes};
use scion_runtime::reference::closest_point::{closest_point_brute, ClosestPoint};
use std::sync::Mutex;

pub use scion_runtime::query::points::uniform_points;

/// Why [`Queries`] never has the kind [`QueryKind::Collide`]: its constructors make hit and
/// closest-point queries only.
const NOT_BATCHED: &str = "collision is one query over two trees (crate::collide), not a batch";

/// Queries of one kind, as the entry's query records.
#[derive(Clone, Debug)]
pub struct Queries {
    /// Their kind.
    pub kind: QueryKind,
    /// The records, back to back.
    pub bytes: Vec<u8>,
    /// The rays of a hit kind (empty otherwise).
    pub rays: Vec<Ray>,
    /// The points of a closest-point query (empty otherwise).
    pub points: Vec<Vec3>,
}

impl Queries {
    /// Hit queries (closest or any) of `rays`.
    pub fn rays(kind: QueryKind, rays: Vec<Ray>) -> Queries {
        assert!(
            matches!(kind, QueryKind::ClosestHit | QueryKind::AnyHit),
            "rays are hit queries"
        );
        Queries {
            kind,
            bytes: rays_to_bytes(&rays),
            rays,
            points: Vec::new(),
        }
    }

    /// Closest-point queries of `points`.
    pub fn points(points: Vec<Vec3>) -> Queries {
        Queries {
            kind: QueryKind::ClosestPoint,
            bytes: points
                .iter()
                .flat_map(|p| [p.x, p.y, p.z])
                .flat_map(f32::to_le_bytes)
                .collect(),
            rays: Vec::new(),
            points,
        }
    }

    /// How many queries.
    pub fn len(&self) -> usize {
        match self.kind {
            QueryKind::ClosestPoint => self.points.len(),
            _ => self.rays.len(),
        }
    }

    /// True when there are none.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The sizes of this kind's query and result records.
    pub fn record_sizes(&self) -> (u64, u64) {
        match self.kind {
            QueryKind::ClosestHit => (32, 8),
            QueryKind::AnyHit => (32, 4),
            QueryKind::ClosestPoint => (12, 20),
            QueryKind::Collide => unreachable!("{NOT_BATCHED}"),
        }
    }

    /// The result records a query starts from.
    pub fn initial_results(&self) -> Vec<u8> {
        match self.kind {
            QueryKind::ClosestHit => self
                .rays
                .iter()
                .flat_map(|r| {
                    let mut b = r.tmax.to_le_bytes().to_vec();
                    b.extend_from_slice(&u32::MAX.to_le_bytes());
                    b
                })
                .collect(),
            QueryKind::AnyHit => vec![0; self.rays.len() * 4],
            QueryKind::ClosestPoint => (0..self.points.len())
                .flat_map(|_| closest_point_bytes(&ClosestPoint::start(f32::INFINITY)))
                .collect(),
            QueryKind::Collide => unreachable!("{NOT_BATCHED}"),
        }
    }

    /// Compares `results` with the reference: for hits, the reference traversal of
    /// `traversed` (the tree the layout traverses: binary or wide, its decoded boxes when
    /// quantized; `crate::hit_reference`'s rule, brute force over `triangles` settling the
    /// answers that differ); for closest points, brute force over `triangles` on the first
    /// `max_brute` points. `Ok` says what was checked; `Err` names the first query whose
    /// answer is wrong, with both answers.
    pub fn check(
        &self,
        triangles: &[Triangle],
        traversed: Traversed,
        results: &[u8],
        max_brute: usize,
        driver: &BatchDriver,
    ) -> Result<String, String> {
        let want = self.expected(triangles, traversed, max_brute, driver)?;
        self.compare(&want, results, triangles)
    }

    /// The reference's answers [`Queries::check`] compares with (computed once, they can be
    /// compared with the results of several layouts that traverse the same tree; closest
    /// points' do not depend on the tree).
    pub fn expected(
        &self,
        triangles: &[Triangle],
        traversed: Traversed,
        max_brute: usize,
        driver: &BatchDriver,
    ) -> Result<Expected, String> {
        match self.kind {
            QueryKind::ClosestHit | QueryKind::AnyHit => Ok(Expected::Hits(
                traversed.hits(&self.rays, driver)?,
                traversed.name(),
            )),
            QueryKind::ClosestPoint => {
                let k = self.points.len().min(max_brute);
                Ok(Expected::Points(brute_points(
                    triangles,
                    &self.points[..k],
                    driver,
                )))
            }
            QueryKind::Collide => unreachable!("{NOT_BATCHED}"),
        }
    }

    /// Compares `results` with the reference's answers `want` (of [`Queries::expected`]); a
    /// hit that differs is settled by brute force over `triangles`
    /// (`crate::hit_reference`).
    pub fn compare(
        &self,
        want: &Expected,
        results: &[u8],
        triangles: &[Triangle],
    ) -> Result<String, String> {
        let word = |i: usize| u32::from_le_bytes(results[i..i + 4].try_into().unwrap());
        match want {
            Expected::Hits(want, name) => {
                let closest = self.kind == QueryKind::ClosestHit;
                let got = |i: usize| Hit::from_best(f32::from_bits(word(8 * i)), word(8 * i + 4));
                let occluded = |i: usize| word(4 * i) != 0;
                let agreement = check_answers(
                    &self.rays,
                    triangles,
                    |i| match closest {
                        true => !got(i).bit_eq(&want[i]),
                        false => occluded(i) != want[i].is_hit(),
                    },
                    |i, brute| match closest {
                        true => got(i).bit_eq(brute) && !want[i].bit_eq(brute),
                        false => {
                            occluded(i) == brute.is_hit() && want[i].is_hit() != brute.is_hit()
                        }
                    },
                    |i| {
                        let answer = match closest {
                            true => format!("{:?}", got(i)),
                            false => format!("occluded {}", word(4 * i)),
                        };
                        format!(
                            "query {i}: the answer differs from the {name}'s: got {answer}, \
                             reference {:?}",
                            want[i]
                        )
                    },
                )?;
                Ok(format!(
                    "{} (checksum of its hits {:016x})",
                    agreement.describe(name, "queries"),
                    hits_checksum(want)
                ))
            }
            Expected::Points(want) => {
                let (n, k) = (self.points.len(), want.len());
                for (i, w) in want.iter().enumerate() {
                    let got = closest_point_from(&results[20 * i..20 * i + 20]);
                    if !got.bit_eq(w) {
                        return Err(format!(
                            "query {i}: the answer differs from the reference: got {got:?}, \
                             reference {w:?}"
                        ));
                    }
                }
                Ok(format!(
                    "identical to brute force on {k} of {n} queries (the first {k})"
                ))
            }
        }
    }
}

/// The reference's answers to a set of queries ([`Queries::expected`]).
#[derive(Clone, Debug)]
pub enum Expected {
    /// The reference traversal's hits, one per ray, and its name.
    Hits(Vec<Hit>, &'static str),
    /// Brute force's closest points of the first points.
    Points(Vec<ClosestPoint>),
}

/// Brute force's closest point of each of `points`, on `driver`'s threads.
fn brute_points(
    triangles: &[Triangle],
    points: &[Vec3],
    driver: &BatchDriver,
) -> Vec<ClosestPoint> {
    let mut want = vec![ClosestPoint::start(f32::INFINITY); points.len()];
    let chunks: Vec<Mutex<&mut [ClosestPoint]>> = want.chunks_mut(BLOCK).map(Mutex::new).collect();
    driver.run(points.len(), |begin, end| {
        let mut out = chunks[begin / BLOCK]
            .lock()
            .unwrap_or_else(|p| p.into_inner());
        for (j, i) in (begin..end).enumerate() {
            out[j] = closest_point_brute(triangles, points[i], f32::INFINITY);
        }
    });
    drop(chunks);
    want
}

/// The 20-byte record of a closest point: distance, primitive id, point.
pub fn closest_point_bytes(c: &ClosestPoint) -> Vec<u8> {
    [
        c.distance.to_bits(),
        c.prim,
        c.point.x.to_bits(),
        c.point.y.to_bits(),
        c.point.z.to_bits(),
    ]
    .into_iter()
    .flat_map(u32::to_le_bytes)
    .collect()
}

/// A closest point from its 20-byte record.
pub fn closest_point_from(b: &[u8]) -> ClosestPoint {
    let w = |i: usize| u32::from_le_bytes(b[4 * i..4 * i + 4].try_into().unwrap());
    ClosestPoint {
        distance: f32::from_bits(w(0)),
        prim: w(1),
        point: Vec3::new(
            f32::from_bits(w(2)),
            f32::from_bits(w(3)),
            f32::from_bits(w(4)),
        ),
    }
}

/// A points file's bytes: 12-byte records, f32 x, y, z little-endian (docs/formats.md). `Err`
/// for a size that is not whole records or a coordinate that is not finite.
pub fn points_from_bytes(bytes: &[u8]) -> Result<Vec<Vec3>, String> {
    if bytes.len() / 12 * 12 != bytes.len() {
        return Err(format!(
            "{} bytes is not a whole number of 12-byte points",
            bytes.len()
        ));
    }
    let f = |b: &[u8], i: usize| f32::from_le_bytes(b[i..i + 4].try_into().unwrap());
    let points: Vec<Vec3> = bytes
        .chunks_exact(12)
        .map(|b| Vec3::new(f(b, 0), f(b, 4), f(b, 8)))
        .collect();
    match points.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(format!("point {i} is not finite: {:?}", points[i])),
        None => Ok(points),
    }
}
