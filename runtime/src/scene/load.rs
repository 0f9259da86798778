//! OBJ loading: a `.obj` file -> [`Scene`] of triangles in file order, through `tobj`.
//!
//! What is read: `v` lines (positions; an optional fourth value `w` divides the three
//! coordinates, as `tobj` does; three extra values are vertex colors and are ignored) and `f`
//! lines. Everything else (normals, texture coordinates, groups, objects, materials, `l` lines)
//! is read by `tobj` but does not change the triangles. A polygon face `f a b c d ...` is
//! triangulated as a fan around its first vertex: `(a, b, c)`, `(a, c, d)`, ... A face with
//! fewer than three vertices is an error naming its line. A file that starts with gzip's magic
//! number is unpacked first (the repository's `scenes/NAME.obj.gz`).
//!
//! Ids: triangle `i` of the file (counting the triangles of fans in order) gets `id == i`, so
//! the scene keeps file order. An empty scene (no faces) is valid.
//!
//! Errors are [`SceneError`]s naming the file and, where it applies, the 1-based line. `tobj`
//! reports what went wrong but not where; `locate` finds the first line that shows the
//! reported problem by re-checking lines with the same rules. Coordinates that are NaN or
//! infinite (including values like `1e39` that overflow `f32`) are rejected: `tobj` accepts
//! them, so every `v` line is checked here, whether or not a face uses it. So are coordinates
//! beyond [`MAX_COORDINATE`] and scenes smaller than [`MIN_EXTENT`], where the triangle test
//! loses hits (docs/runtime.md, "Supported coordinate range").

use std::io::{Cursor, Read};
use std::path::{Path, PathBuf};

use super::{check_count, Scene, SceneError, MAX_COORDINATE, MIN_EXTENT};
use crate::geom::{Triangle, Vec3};

/// Loads an OBJ file, plain or gzip-compressed (`NAME.obj.gz`, recognized by its first bytes,
/// whatever its name), see the module documentation for what is read and rejected.
pub fn load_obj(path: impl AsRef<Path>) -> Result<Scene, SceneError> {
    let path = path.as_ref();
    let bytes = read_unpacked(path)?;
    let text = std::str::from_utf8(&bytes).map_err(|e| SceneError::NotText {
        path: path.to_path_buf(),
        line: 1 + bytes[..e.valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count(),
    })?;
    parse_obj(path, &scene_name(path), text)
}

/// The file's bytes, unpacked when they start with gzip's magic number.
pub(crate) fn read_unpacked(path: &Path) -> Result<Vec<u8>, SceneError> {
    let bytes = std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if !bytes.starts_with(&[0x1f, 0x8b]) {
        return Ok(bytes);
    }
    let mut unpacked = Vec::with_capacity(bytes.len() * 4);
    flate2::read::MultiGzDecoder::new(bytes.as_slice())
        .read_to_end(&mut unpacked)
        .map_err(|source| SceneError::Compressed {
            path: path.to_path_buf(),
            source,
        })?;
    Ok(unpacked)
}

/// A scene's name: the file name without `.gz` and `.obj` (`scenes/bunny.obj.gz` -> `bunny`).
pub fn scene_name(path: &Path) -> String {
    let file = path
        .file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let file = file.strip_suffix(".gz").unwrap_or(&file);
    let file = file.strip_suffix(".obj").unwrap_or(file);
    file.to_string()
}

/// Parses OBJ text already in memory; `path` is used only in error messages.
pub fn parse_obj(path: &Path, name: &str, text: &str) -> Result<Scene, SceneError> {
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    check_faces(path, text)?;
    let (models, _materials) = tobj::load_obj_buf(
        &mut Cursor::new(text.as_bytes()),
        &options,
        // Materials never change the geometry: do not open .mtl files.
        |_| Err(tobj::LoadError::OpenFileFailed),
    )
    .map_err(|e| locate(path, text, e))?;

    check_vertices(path, text)?;

    let count: usize = models.iter().map(|m| m.mesh.indices.len() / 3).sum();
    check_count(path, count)?;
    let mut triangles = Vec::with_capacity(count);
    for model in &models {
        let pos = &model.mesh.positions;
        let vertex = |i: u32| {
            let i = i as usize * 3;
            Vec3::new(pos[i], pos[i + 1], pos[i + 2])
        };
        for face in model.mesh.indices.chunks_exact(3) {
            let id = triangles.len() as u32;
            triangles.push(Triangle::new(
                vertex(face[0]),
                vertex(face[1]),
                vertex(face[2]),
                id,
            ));
        }
    }
    let scene = Scene::new(name, triangles);
    check_extent(path, &scene)?;
    Ok(scene)
}

/// Refuses a scene whose box is smaller than [`MIN_EXTENT`] (and not a single point).
fn check_extent(path: &Path, scene: &Scene) -> Result<(), SceneError> {
    if scene.is_empty() {
        return Ok(());
    }
    let b = scene.bounds();
    let extent = (b.high.x - b.low.x)
        .max(b.high.y - b.low.y)
        .max(b.high.z - b.low.z);
    if extent > 0.0 && extent < MIN_EXTENT {
        return Err(SceneError::OutOfRange {
            path: path.to_path_buf(),
            line: None,
            what: format!(
                "the scene's box is only {extent:e} across (from ({}, {}, {}) to ({}, {}, {}))",
                b.low.x, b.low.y, b.low.z, b.high.x, b.high.y, b.high.z
            ),
        });
    }
    Ok(())
}

/// The lines of `text` as `tobj` sees them: split on `\n`, a trailing `\r` dropped, numbered
/// from 1.
fn lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.split('\n')
        .enumerate()
        .map(|(i, l)| (i + 1, l.strip_suffix('\r').unwrap_or(l)))
}

/// Rejects faces of fewer than three vertices (before `tobj`, which drops two-vertex faces
/// and refuses shorter ones without a line).
fn check_faces(path: &Path, text: &str) -> Result<(), SceneError> {
    for (line_no, line) in lines(text) {
        let mut words = line.split_whitespace();
        if words.next() != Some("f") {
            continue;
        }
        let vertices = words.count();
        if vertices < 3 {
            return Err(SceneError::ShortFace {
                path: path.to_path_buf(),
                line: line_no,
                vertices,
                text: line.trim().to_string(),
            });
        }
    }
    Ok(())
}

/// Rejects NaN, infinite and out-of-range coordinates on every `v` line (after the `w`
/// division).
fn check_vertices(path: &Path, text: &str) -> Result<(), SceneError> {
    let mut vertex = 0usize;
    for (line_no, line) in lines(text) {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        vertex += 1;
        // tobj accepted the file, so the first three values parse.
        let mut xyz = [0f32; 3];
        for c in &mut xyz {
            *c = words
                .next()
                .and_then(|w| w.parse().ok())
                .unwrap_or(f32::NAN);
        }
        // Exactly one more value is `w`, which divides (three more are a color).
        if let (Some(w), None) = (words.next(), words.next()) {
            let w: f32 = w.parse().unwrap_or(f32::NAN);
            for c in &mut xyz {
                *c /= w;
            }
        }
        if xyz.iter().any(|c| !c.is_finite()) {
            return Err(SceneError::NonFiniteCoordinate {
                path: path.to_path_buf(),
                line: line_no,
                vertex,
                text: line.trim().to_string(),
            });
        }
        if let Some(c) = xyz.iter().find(|c| c.abs() > MAX_COORDINATE) {
            return Err(SceneError::OutOfRange {
                path: path.to_path_buf(),
                line: Some(line_no),
                what: format!(
                    "vertex {vertex} has the coordinate {c:e}: `{}`",
                    line.trim()
                ),
            });
        }
    }
    Ok(())
}

/// One vertex reference of a face, `v/vt/vn`, as written (each part optional).
type FaceRef = [Option<isize>; 3];

/// Parses one face word by `tobj`'s rules; `None` when `tobj` would reject it.
fn parse_face_ref(word: &str) -> Option<FaceRef> {
    let mut refs: FaceRef = [None; 3];
    for (i, part) in word.split('/').enumerate() {
        if part.is_empty() {
            continue;
        }
        let value: isize = part.parse().ok()?;
        *refs.get_mut(i)? = Some(value);
    }
    Some(refs)
}

/// True when `count` floats parse from the start of `words` (extra words are ignored).
fn floats_ok(words: &[&str], count: usize) -> bool {
    words.len() >= count && words[..count].iter().all(|w| w.parse::<f32>().is_ok())
}

/// True when a `v` line's values are accepted by `tobj`.
fn vertex_line_ok(words: &[&str]) -> bool {
    if !floats_ok(words, 3) {
        return false;
    }
    match words.len() - 3 {
        0 | 3 => true,
        1 => matches!(words[3].parse::<f32>(), Ok(w) if w != 0.0),
        _ => false,
    }
}

/// Resolves a written index (1-based, or negative = relative to `seen` elements so far) to a
/// 0-based index, or `None` when it is out of `0..total`.
fn resolve(index: isize, seen: usize, total: usize) -> Option<usize> {
    let i = if index < 0 {
        seen as isize + index
    } else {
        index - 1
    };
    (i >= 0 && (i as usize) < total).then_some(i as usize)
}

/// Counts of `v`, `vt`, `vn` lines.
#[derive(Clone, Copy, Default)]
struct Counts {
    v: usize,
    vt: usize,
    vn: usize,
}

fn count_elements(text: &str) -> Counts {
    let mut c = Counts::default();
    for (_, line) in lines(text) {
        match line.split_whitespace().next() {
            Some("v") => c.v += 1,
            Some("vt") => c.vt += 1,
            Some("vn") => c.vn += 1,
            _ => {}
        }
    }
    c
}

/// Which lane of a face reference an out-of-bounds error is about.
#[derive(Clone, Copy, PartialEq)]
enum Lane {
    Position = 0,
    Texcoord = 1,
    Normal = 2,
}

/// Finds the first face with a reference out of range in `lane`. With `strict`, positive
/// indices are checked against the elements declared so far rather than in the whole file
/// (tobj resolves faces when an object ends, so a later vertex may or may not count).
fn find_out_of_range(text: &str, lane: Lane, strict: bool) -> Option<(usize, isize, String)> {
    let totals = count_elements(text);
    let mut seen = Counts::default();
    for (line_no, line) in lines(text) {
        let words: Vec<&str> = line.split_whitespace().collect();
        match words.first().copied() {
            Some("v") => seen.v += 1,
            Some("vt") => seen.vt += 1,
            Some("vn") => seen.vn += 1,
            Some("f") if words.len() >= 4 => {
                let (seen_n, total_n) = match lane {
                    Lane::Position => (seen.v, totals.v),
                    Lane::Texcoord => (seen.vt, totals.vt),
                    Lane::Normal => (seen.vn, totals.vn),
                };
                // tobj ignores texture and normal indices when the file has none.
                if lane != Lane::Position && total_n == 0 {
                    continue;
                }
                let limit = if strict { seen_n } else { total_n };
                for word in &words[1..] {
                    let Some(refs) = parse_face_ref(word) else {
                        continue;
                    };
                    if let Some(index) = refs[lane as usize] {
                        if resolve(index, seen_n, limit).is_none() {
                            return Some((line_no, index, line.trim().to_string()));
                        }
                    } else if lane == Lane::Position {
                        // A missing position index is index 0 for tobj: out of range.
                        return Some((line_no, 0, line.trim().to_string()));
                    }
                }
            }
            _ => {}
        }
    }
    None
}

/// Finds the first line whose keyword is one of `keys` and which `ok` rejects.
fn find_line(text: &str, keys: &[&str], ok: impl Fn(&[&str]) -> bool) -> Option<(usize, String)> {
    lines(text).find_map(|(line_no, line)| {
        let words: Vec<&str> = line.split_whitespace().collect();
        let key = *words.first()?;
        (keys.contains(&key) && !ok(&words[1..])).then(|| (line_no, line.trim().to_string()))
    })
}

/// Turns a `tobj` error into a [`SceneError`], finding the line it is about.
fn locate(path: &Path, text: &str, error: tobj::LoadError) -> SceneError {
    use tobj::LoadError as E;
    let path: PathBuf = path.to_path_buf();
    let found = match error {
        E::PositionParseError | E::ScalingByZeroError | E::ColorParseError => {
            find_line(text, &["v"], vertex_line_ok)
        }
        E::TexcoordParseError => find_line(text, &["vt"], |w| floats_ok(w, 2)),
        E::NormalParseError => find_line(text, &["vn"], |w| floats_ok(w, 3)),
        E::FaceParseError => find_line(text, &["f", "l"], |w| {
            w.iter().all(|x| parse_face_ref(x).is_some())
        }),
        E::MaterialParseError => find_line(text, &["usemtl"], |w| !w.is_empty()),
        E::FaceVertexOutOfBounds | E::FaceTexCoordOutOfBounds | E::FaceNormalOutOfBounds => {
            let lane = match error {
                E::FaceVertexOutOfBounds => Lane::Position,
                E::FaceTexCoordOutOfBounds => Lane::Texcoord,
                _ => Lane::Normal,
            };
            let hit = find_out_of_range(text, lane, false)
                .or_else(|| find_out_of_range(text, lane, true));
            if lane == Lane::Position {
                let vertex_count = count_elements(text).v;
                return match hit {
                    Some((line, index, _)) => SceneError::FaceIndexOutOfRange {
                        path,
                        line: Some(line),
                        index: index as i64,
                        vertex_count,
                    },
                    None => SceneError::FaceIndexOutOfRange {
                        path,
                        line: None,
                        index: 0,
                        vertex_count,
                    },
                };
            }
            hit.map(|(line, _, text)| (line, text))
        }
        _ => None,
    };
    let message = error.to_string();
    match found {
        Some((line, text)) => SceneError::Malformed {
            path,
            line: Some(line),
            message,
            text: Some(text),
        },
        None => SceneError::Malformed {
            path,
            line: None,
            message,
            text: None,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<Scene, SceneError> {
        parse_obj(Path::new("mem.obj"), "mem", text)
    }

    #[test]
    fn triangles_keep_file_order_and_polygons_become_fans() {
        let s = parse(
            "# a quad and a pentagon\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv -1 0.5 0\n\
             f 1 2 3 4\nf 1 2 3\no second\nf 1/1 2 3 4 5\n",
        );
        // The pentagon line uses a texture index although the file has none: tobj ignores it.
        let s = s.unwrap();
        assert_eq!(s.len(), 6);
        for (i, t) in s.triangles.iter().enumerate() {
            assert_eq!(t.id as usize, i);
        }
        let v = |x: f32, y: f32| Vec3::new(x, y, 0.0);
        assert_eq!(s.triangles[0].p2, v(1.0, 1.0));
        assert_eq!(
            (s.triangles[1].p0, s.triangles[1].p1),
            (v(0.0, 0.0), v(1.0, 1.0))
        );
        assert_eq!(s.triangles[1].p2, v(0.0, 1.0));
        assert_eq!(s.triangles[2].p1, v(1.0, 0.0));
        assert_eq!(s.triangles[5].p2, v(-1.0, 0.5));
    }

    #[test]
    fn relative_indices_and_w_are_honored() {
        let s = parse("v 0 0 0\nv 2 0 0 2\nv 0 1 0\nf -3 -2 -1\n").unwrap();
        assert_eq!(s.triangles[0].p1, Vec3::new(1.0, 0.0, 0.0));
    }

    #[test]
    fn empty_scene_is_valid() {
        assert!(parse("# nothing\n").unwrap().is_empty());
        assert!(parse("v 0 0 0\nv 1 0 0\nl 1 2\n").unwrap().is_empty());
    }

    #[test]
    fn errors_name_the_line() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 x 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(e.line(), Some(3), "{e}");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n").unwrap_err();
        assert!(
            matches!(e, SceneError::FaceIndexOutOfRange { index: 4, .. }),
            "{e}"
        );
        assert_eq!(e.line(), Some(4));
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n").unwrap_err();
        assert_eq!(e.line(), Some(4), "{e}");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n").unwrap_err();
        assert_eq!(e.line(), Some(4), "{e}");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/a\n").unwrap_err();
        assert_eq!(e.line(), Some(4), "{e}");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(e.line(), Some(3), "{e}");
        let e = parse("v 0 0 0\nvn 1 0\nv 0 1 0\n").unwrap_err();
        assert_eq!(e.line(), Some(2), "{e}");
    }

    #[test]
    fn non_finite_coordinates_are_rejected_with_their_line() {
        for bad in ["nan", "inf", "-inf", "1e39", "NaN"] {
            let text = format!("v 0 0 0\n# c\nv 1 0 0\nv 0 {bad} 0\nf 1 2 3\n");
            let e = parse(&text).unwrap_err();
            match &e {
                SceneError::NonFiniteCoordinate { line, vertex, .. } => {
                    assert_eq!((*line, *vertex), (4, 3), "{e}");
                }
                other => panic!("expected NonFiniteCoordinate, got {other}"),
            }
        }
        // A tiny w overflows the division.
        let e = parse("v 0 0 0\nv 1e30 0 0 1e-30\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(e.line(), Some(2), "{e}");
    }

    #[test]
    fn short_faces_are_errors_with_their_line() {
        for (face, n) in [("f 1 2", 2), ("f 3", 1), ("f", 0)] {
            let text = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n{face}\n");
            let e = parse(&text).unwrap_err();
            match &e {
                SceneError::ShortFace { line, vertices, .. } => {
                    assert_eq!((*line, *vertices), (5, n), "{e}")
                }
                other => panic!("expected ShortFace, got {other}"),
            }
            assert!(
                e.to_string()
                    .starts_with("mem.obj:5: a face needs at least 3"),
                "{e}"
            );
        }
    }

    #[test]
    fn coordinates_outside_the_supported_range_are_refused() {
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 -2e19 0\nf 1 2 3\n").unwrap_err();
        assert!(
            matches!(e, SceneError::OutOfRange { line: Some(3), .. }),
            "{e}"
        );
        assert!(e.to_string().contains("-2e19"), "{e}");
        // At the limit it loads.
        assert_eq!(
            parse("v 0 0 0\nv 1e12 0 0\nv 0 1 0\nf 1 2 3\n")
                .unwrap()
                .len(),
            1
        );
        // A scene smaller than the smallest extent, with its box in the message.
        let e = parse("v 1 1 1\nv 1.0000001 1 1\nv 1 1 1\nf 1 2 3\n");
        assert!(e.is_ok(), "1e-7 across is in range");
        let e = parse("v 0 0 0\nv 1e-13 0 0\nv 0 1e-13 0\nf 1 2 3\n").unwrap_err();
        assert!(
            matches!(e, SceneError::OutOfRange { line: None, .. }),
            "{e}"
        );
        assert!(e.to_string().contains("across"), "{e}");
        // A single point (extent 0) and an empty scene are not out of range.
        assert!(parse("v 5 5 5\nf 1 1 1\n").is_ok());
        assert!(parse("").is_ok());
    }

    #[test]
    fn names_drop_obj_and_gz() {
        assert_eq!(scene_name(Path::new("scenes/bunny.obj.gz")), "bunny");
        assert_eq!(scene_name(Path::new("a/b.obj")), "b");
        assert_eq!(scene_name(Path::new("mesh")), "mesh");
    }
}
