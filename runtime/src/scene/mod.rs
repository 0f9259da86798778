//! Scenes: a named list of triangles in file order, loaded from OBJ ([`load`]), transformed
//! and instanced ([`transform`]), or generated as hard test cases ([`gen`]); [`manifest`] lists
//! the real scenes and finds their folder.
//!
//! Input: OBJ files or parameters; output: [`Scene`], whose triangle `i` has `id == i` unless
//! a transformation composed several scenes (then ids are renumbered, see
//! [`transform::instances`]). Scenes feed the builders of `bvh` (paper §7, §9 set-up).

pub mod gen;
pub mod load;
pub mod manifest;
pub mod strands;
pub mod transform;

use std::fmt;
use std::path::PathBuf;

use crate::geom::{Aabb, Triangle};

pub use load::load_obj;
pub use transform::{instances, Transform};

/// A triangle soup with a name for reports.
#[derive(Clone, Debug, PartialEq)]
pub struct Scene {
    /// A short name (the file stem for loaded scenes).
    pub name: String,
    /// Triangles; `triangles[i].id` is the original face index.
    pub triangles: Vec<Triangle>,
}

impl Scene {
    /// A scene from triangles whose ids are already set.
    pub fn new(name: impl Into<String>, triangles: Vec<Triangle>) -> Scene {
        Scene {
            name: name.into(),
            triangles,
        }
    }

    /// The box of all triangles ([`Aabb::EMPTY`] for an empty scene).
    pub fn bounds(&self) -> Aabb {
        self.triangles
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// True for a scene without triangles (a valid scene).
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }
}

/// The largest coordinate magnitude a loaded scene may have: Moller-Trumbore's `t` multiplies
/// three coordinate differences, which overflow `f32` from about `1e13` (docs/runtime.md).
pub const MAX_COORDINATE: f32 = 1e12;

/// The smallest extent (longest side of the scene's box) a loaded scene with any extent may
/// have: below it those products underflow and hits are lost (docs/runtime.md).
pub const MIN_EXTENT: f32 = 1e-12;

/// Why a scene could not be loaded or composed.
///
/// Display names the file and, where one applies, the 1-based line, as `path:line: message`.
#[derive(Debug)]
pub enum SceneError {
    /// The file is missing or could not be read.
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The file is not UTF-8 text.
    NotText {
        /// The file.
        path: PathBuf,
        /// 1-based line of the first invalid byte.
        line: usize,
    },
    /// A line the OBJ parser rejected.
    Malformed {
        /// The file.
        path: PathBuf,
        /// 1-based line, when it could be found.
        line: Option<usize>,
        /// The parser's description of the problem.
        message: String,
        /// The offending line's text (trimmed), when found.
        text: Option<String>,
    },
    /// A face refers to a vertex that does not exist.
    FaceIndexOutOfRange {
        /// The file.
        path: PathBuf,
        /// 1-based line of the face, when it could be found.
        line: Option<usize>,
        /// The index as written in the file (1-based, or negative for relative).
        index: i64,
        /// How many vertices the file declares.
        vertex_count: usize,
    },
    /// A vertex coordinate is NaN or ±inf (also after the optional `w` division).
    NonFiniteCoordinate {
        /// The file.
        path: PathBuf,
        /// 1-based line of the `v` line.
        line: usize,
        /// 1-based vertex number (the k-th `v` line).
        vertex: usize,
        /// The line's text.
        text: String,
    },
    /// A gzip-compressed scene file (`NAME.obj.gz`) that does not unpack.
    Compressed {
        /// The file.
        path: PathBuf,
        /// What the decompressor reported.
        source: std::io::Error,
    },
    /// A face (`f` line) with fewer than three vertices: it has no triangle, and dropping it
    /// would lose geometry without a word.
    ShortFace {
        /// The file.
        path: PathBuf,
        /// 1-based line of the face.
        line: usize,
        /// How many vertices it lists.
        vertices: usize,
        /// The line's text.
        text: String,
    },
    /// Coordinates outside the range where the triangle test is exact enough to find every hit
    /// ([`MAX_COORDINATE`], [`MIN_EXTENT`]; docs/runtime.md, "Supported coordinate range").
    OutOfRange {
        /// The file.
        path: PathBuf,
        /// 1-based line of the first `v` line beyond [`MAX_COORDINATE`], when that is the cause.
        line: Option<usize>,
        /// What is out of range, with its value.
        what: String,
    },
    /// A binary scene file (a strand scene's `.hair`) that does not hold what its header says.
    Invalid {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// More triangles than ids: `u32::MAX` is reserved for "no primitive".
    TooManyTriangles {
        /// Where the triangles came from (file or composition).
        path: PathBuf,
        /// How many there would be.
        count: u64,
    },
}

impl SceneError {
    /// The file the error is about.
    pub fn path(&self) -> &std::path::Path {
        match self {
            SceneError::Io { path, .. }
            | SceneError::NotText { path, .. }
            | SceneError::Malformed { path, .. }
            | SceneError::FaceIndexOutOfRange { path, .. }
            | SceneError::NonFiniteCoordinate { path, .. }
            | SceneError::Compressed { path, .. }
            | SceneError::ShortFace { path, .. }
            | SceneError::OutOfRange { path, .. }
            | SceneError::Invalid { path, .. }
            | SceneError::TooManyTriangles { path, .. } => path,
        }
    }

    /// The 1-based line the error is about, when there is one.
    pub fn line(&self) -> Option<usize> {
        match self {
            SceneError::NotText { line, .. }
            | SceneError::NonFiniteCoordinate { line, .. }
            | SceneError::ShortFace { line, .. } => Some(*line),
            SceneError::Malformed { line, .. }
            | SceneError::FaceIndexOutOfRange { line, .. }
            | SceneError::OutOfRange { line, .. } => *line,
            SceneError::Io { .. }
            | SceneError::Compressed { .. }
            | SceneError::Invalid { .. }
            | SceneError::TooManyTriangles { .. } => None,
        }
    }
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let path = self.path().display();
        match self.line() {
            Some(line) => write!(f, "{path}:{line}: ")?,
            None => write!(f, "{path}: ")?,
        }
        match self {
            SceneError::Io { source, .. } => write!(f, "cannot read the scene file: {source}"),
            SceneError::NotText { .. } => write!(f, "the file is not UTF-8 text"),
            SceneError::Malformed { message, text, .. } => {
                write!(f, "malformed OBJ line ({message})")?;
                if let Some(text) = text {
                    write!(f, ": `{text}`")?;
                }
                Ok(())
            }
            SceneError::FaceIndexOutOfRange {
                index,
                vertex_count,
                ..
            } => write!(
                f,
                "face vertex index {index} is out of range (the file has {vertex_count} vertices, \
                 valid indices are 1..={vertex_count} or -1..=-{vertex_count})"
            ),
            SceneError::NonFiniteCoordinate { vertex, text, .. } => write!(
                f,
                "vertex {vertex} has a NaN or infinite coordinate: `{text}` \
                 (coordinates must be finite f32 values)"
            ),
            SceneError::Compressed { source, .. } => write!(
                f,
                "the gzip-compressed scene file does not unpack: {source}"
            ),
            SceneError::ShortFace { vertices, text, .. } => write!(
                f,
                "a face needs at least 3 vertices, this one lists {vertices}: `{text}` \
                 (a line of two vertices is an `l` line)"
            ),
            SceneError::OutOfRange { what, .. } => write!(
                f,
                "{what}; the supported range is coordinates of magnitude at most {MAX_COORDINATE:e} \
                 and a scene extent of at least {MIN_EXTENT:e} (beyond it the f32 triangle test \
                 overflows or underflows and hits are lost); scale the scene into that range"
            ),
            SceneError::Invalid { message, .. } => write!(f, "{message}"),
            SceneError::TooManyTriangles { count, .. } => write!(
                f,
                "{count} triangles is too many: ids are u32 and u32::MAX means \"no primitive\""
            ),
        }
    }
}

impl std::error::Error for SceneError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            SceneError::Io { source, .. } | SceneError::Compressed { source, .. } => Some(source),
            _ => None,
        }
    }
}

/// Checks that `count` triangles can be numbered with `u32` ids below `u32::MAX`.
pub(crate) fn check_count(path: &std::path::Path, count: usize) -> Result<(), SceneError> {
    if count as u64 >= u32::MAX as u64 {
        return Err(SceneError::TooManyTriangles {
            path: path.to_path_buf(),
            count: count as u64,
        });
    }
    Ok(())
}
