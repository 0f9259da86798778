//! Malformed OBJ files: every error names the file and, where it applies, the 1-based line.
//! The files are written into a scratch folder.

use crate::common;

use scion_runtime::scene::{load_obj, SceneError};

/// Writes `text` as `name` in a scratch folder, loads it, and returns the error's message
/// (which must start with the file's path) and line.
fn load_err(dir: &std::path::Path, name: &str, text: &[u8]) -> (String, Option<usize>) {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    let e = load_obj(&path).expect_err(name);
    let msg = e.to_string();
    assert!(
        msg.starts_with(&path.display().to_string()),
        "message does not name the file: {msg}"
    );
    (msg, e.line())
}

#[test]
fn malformed_files_name_file_and_line() {
    let dir = common::scratch("load_errors");
    let head = "# header\nv 0 0 0\nv 1 0 0\nv 0 1 0\n";
    let cases: &[(&str, String, usize, &str)] = &[
        (
            "bad_vertex.obj",
            format!("{head}v 1 two 3\nf 1 2 3\n"),
            5,
            "position parse error",
        ),
        (
            "short_vertex.obj",
            format!("{head}v 1 2\nf 1 2 3\n"),
            5,
            "position parse error",
        ),
        (
            "zero_w.obj",
            format!("{head}v 1 2 3 0\nf 1 2 3\n"),
            5,
            "scaling",
        ),
        (
            "bad_face.obj",
            format!("{head}f 1 2 x\n"),
            5,
            "face parse error",
        ),
        (
            "too_many_slashes.obj",
            format!("{head}f 1/1/1/1 2 3\n"),
            5,
            "face parse error",
        ),
        (
            "out_of_range.obj",
            format!("{head}f 1 2 3\nf 1 2 9\n"),
            6,
            "out of range",
        ),
        (
            "negative_out_of_range.obj",
            format!("{head}f 1 2 -4\n"),
            5,
            "index -4",
        ),
        ("zero_index.obj", format!("{head}f 0 1 2\n"), 5, "index 0"),
        (
            "bad_normal.obj",
            format!("{head}vn 0 0\nf 1 2 3\n"),
            5,
            "normal parse error",
        ),
        (
            "bad_texcoord.obj",
            format!("{head}vt x 0\nf 1 2 3\n"),
            5,
            "texcoord parse error",
        ),
        (
            "nan.obj",
            format!("{head}v nan 0 0\nf 1 2 4\n"),
            5,
            "NaN or infinite",
        ),
        (
            "inf.obj",
            format!("{head}f 1 2 3\nv 0 -inf 0\n"),
            6,
            "vertex 4",
        ),
        (
            "overflow.obj",
            format!("{head}v 0 0 1e39\n"),
            5,
            "NaN or infinite",
        ),
        (
            "crlf.obj",
            format!("{head}f 1 2 3\r\nv 1 2\r\n").replace('\n', "\r\n"),
            6,
            "position",
        ),
    ];
    for (name, text, line, needle) in cases {
        let (msg, got) = load_err(&dir, name, text.as_bytes());
        assert_eq!(got, Some(*line), "{name}: {msg}");
        assert!(msg.contains(&format!(":{line}: ")), "{name}: {msg}");
        assert!(msg.contains(needle), "{name}: `{msg}` lacks `{needle}`");
    }
    let (msg, line) = load_err(&dir, "binary.obj", b"v 0 0 0\nv 1 0 0\n\xff\xfe\n");
    assert_eq!(line, Some(3), "{msg}");
    assert!(msg.contains("UTF-8"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn missing_file_and_directory_are_io_errors() {
    let dir = common::scratch("load_missing");
    let missing = dir.join("nope.obj");
    let e = load_obj(&missing).unwrap_err();
    assert!(matches!(e, SceneError::Io { .. }));
    assert!(
        e.to_string().starts_with(&missing.display().to_string()),
        "{e}"
    );
    assert!(e.to_string().contains("cannot read"), "{e}");
    assert!(matches!(load_obj(&dir).unwrap_err(), SceneError::Io { .. }));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn valid_edge_cases_load() {
    let dir = common::scratch("load_ok");
    let cases: &[(&str, &str, usize)] = &[
        ("empty.obj", "", 0),
        ("comments.obj", "# only\n# comments\n", 0),
        ("vertices_only.obj", "v 0 0 0\nv 1 1 1\n", 0),
        ("lines_only.obj", "v 0 0 0\nv 1 1 1\nl 1 2\n", 0),
        (
            "quad.obj",
            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n",
            2,
        ),
        (
            "hexagon.obj",
            "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 2 0\nv -1 1 0\nf 1 2 3 4 5 6\n",
            4,
        ),
        (
            "full.obj",
            "mtllib missing.mtl\no a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvn 0 0 1\nusemtl m\n\
             f 1/1/1 2/1/1 3/1/1\ng b\ns 1\nf -3//1 -2//1 -1//1\n",
            2,
        ),
    ];
    for (name, text, count) in cases {
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        let s = load_obj(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.len(), *count, "{name}");
        assert!(s
            .triangles
            .iter()
            .enumerate()
            .all(|(i, t)| t.id as usize == i));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn gzip_compressed_files_load_like_plain_ones() {
    use std::io::Write;
    let dir = common::scratch("load_gz");
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3 4\n";
    let plain = dir.join("quad.obj");
    std::fs::write(&plain, text).unwrap();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::best());
    gz.write_all(text.as_bytes()).unwrap();
    let packed = gz.finish().unwrap();
    let gz_path = dir.join("quad.obj.gz");
    std::fs::write(&gz_path, &packed).unwrap();
    let a = load_obj(&plain).unwrap();
    let b = load_obj(&gz_path).unwrap();
    assert_eq!(a, b, "same triangles and the same name");
    assert_eq!(b.name, "quad");
    // Errors inside a compressed file name the file and the unpacked text's line.
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    gz.write_all(b"v 0 0 0\nv 1 0 0\nf 1 2\n").unwrap();
    let (msg, line) = load_err(&dir, "short.obj.gz", &gz.finish().unwrap());
    assert_eq!(line, Some(3), "{msg}");
    // A truncated archive is an error, not a shorter scene.
    let (msg, line) = load_err(&dir, "cut.obj.gz", &packed[..packed.len() / 2]);
    assert_eq!(line, None, "{msg}");
    assert!(msg.contains("does not unpack"), "{msg}");
    let _ = std::fs::remove_dir_all(&dir);
}
