//! Queries: ray generators ([`rays`]), closest-point query points ([`points`]) and the binary
//! query/result files ([`io`]).
//!
//! Input: a scene box and a seed, or a file; output: `Vec<Ray>` / `Vec<Hit>`. These are the
//! workloads of the paper's evaluation (§9: primary and secondary rays).

pub mod io;
pub mod points;
pub mod rays;

pub use io::{
    hits_checksum, read_hits, read_rays, write_hits, write_rays, write_whole, QueryFileError,
};
pub use rays::{axis_rays, primary_rays, primary_rays_n, secondary_rays, Camera};
