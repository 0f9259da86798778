//! `scionc`'s exit statuses and output files, as `--help` promises them: 2 for a bad command
//! line, 1 for input errors and for output that cannot be written (a full disk: `/dev/full`),
//! `-o` never overwriting an input, and an output file written whole (no temporary left).

use std::path::PathBuf;
use std::process::{Command, Output};

fn scionc(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_scionc"))
        .args(args)
        .output()
        .expect("runs scionc")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("scion-driver-io-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn a_bad_command_line_is_status_2() {
    let o = scionc(&[]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("E0903"), "{}", stderr(&o));
    let o = scionc(&["--passes=no-such-pass", "x.scion"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    // An input error is 1.
    let dir = scratch("bad-input");
    let f = dir.join("f.scion");
    std::fs::write(&f, "func f(x: f32) -> f32 = y\n").unwrap();
    let o = scionc(&["--emit=check", f.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn output_that_cannot_be_written_is_an_error() {
    let dir = scratch("full");
    let f = dir.join("f.scion");
    std::fs::write(&f, "func f(x: f32) -> f32 = x + 1.0\n").unwrap();
    if std::path::Path::new("/dev/full").exists() {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_scionc"))
            .args(["--no-prelude", "--emit=tree", f.to_str().unwrap()])
            .stdout(full)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("cannot write standard output"),
            "{}",
            stderr(&o)
        );
    } else {
        eprintln!("skip: no /dev/full here");
    }
    let o = scionc(&[
        "--no-prelude",
        "--emit=tree",
        "-o",
        dir.join("missing/out.tree").to_str().unwrap(),
        f.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("E0902"), "{}", stderr(&o));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn output_files_are_whole_and_never_an_input() {
    let dir = scratch("files");
    let f = dir.join("f.scion");
    let text = "func f(x: f32) -> f32 = x + 1.0\n";
    std::fs::write(&f, text).unwrap();
    // `-o` onto the input (also through another spelling of its path) is refused.
    let other = dir.join(".").join("f.scion");
    for out in [&f, &other] {
        let o = scionc(&[
            "--no-prelude",
            "--emit=ast",
            "-o",
            out.to_str().unwrap(),
            f.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("would overwrite the input"),
            "{}",
            stderr(&o)
        );
        assert_eq!(std::fs::read_to_string(&f).unwrap(), text);
    }
    // A written output replaces the old file whole and leaves no temporary behind.
    let out = dir.join("out.tree");
    std::fs::write(&out, "old").unwrap();
    let o = scionc(&[
        "--no-prelude",
        "--emit=tree",
        "-o",
        out.to_str().unwrap(),
        f.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(std::fs::read_to_string(&out).unwrap().contains("func @f("));
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.ends_with(".tmp")), "{names:?}");
    let _ = std::fs::remove_dir_all(&dir);
}
