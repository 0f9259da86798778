//! What the `scion` command tests share: a scratch folder per test, running `scion`, and a
//! small scene.

#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// A fresh folder for test `test` of suite `suite`.
pub fn scratch(suite: &str, test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("scion-{suite}-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create scratch folder");
    dir
}

/// Runs the `scion` built for these tests.
pub fn scion(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_scion"))
        .args(args)
        .output()
        .expect("run scion")
}

/// Writes `body` as `name` in `dir`; its path as text.
pub fn write(dir: &std::path::Path, name: &str, body: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    p.display().to_string()
}

/// Asserts that `o` succeeded and its report contains `want`.
pub fn succeeds_with(o: &Output, want: &str) {
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    assert!(out.contains(want), "`{want}` not in:\n{out}");
}

/// Asserts that `o` exited with `code` and its error contains `want`.
pub fn fails_with(o: &Output, code: i32, want: &str) {
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(code), "{err}");
    assert!(err.contains(want), "`{want}` not in:\n{err}");
}

/// Output bytes as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A unit cube's six faces as 12 triangles.
pub const CUBE: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
f 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

/// A soup of `n` small triangles in the unit cube (a deterministic LCG), as OBJ text.
pub fn soup(n: usize) -> String {
    let mut state = 12345u64;
    let mut f = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 40) as f32) / (1u64 << 24) as f32
    };
    let mut obj = String::new();
    for i in 0..n {
        let c = [f(), f(), f()];
        for _ in 0..3 {
            obj.push_str(&format!(
                "v {} {} {}\n",
                c[0] + 0.1 * f(),
                c[1] + 0.1 * f(),
                c[2] + 0.1 * f()
            ));
        }
        obj.push_str(&format!("f {} {} {}\n", 3 * i + 1, 3 * i + 2, 3 * i + 3));
    }
    obj
}
