//! `scionc` built without the `backends` feature (`cargo test -p scion-compiler
//! --no-default-features`, part of scripts/test.sh): the outputs up to `lo` work, and the ones
//! that need a code generator are error E0922, not a crash or silence. With the feature (the
//! default) the test is not compiled: lit covers those outputs.

#[cfg(not(feature = "backends"))]
#[test]
fn machine_code_outputs_say_they_need_a_code_generator() {
    let dir = std::env::temp_dir().join(format!("scion-nobackends-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let src = dir.join("f.scion");
    std::fs::write(&src, "func f(x: f32) -> f32 = x + 1.0\n").unwrap();
    let scionc = env!("CARGO_BIN_EXE_scionc");
    let run = |emit: &str| {
        std::process::Command::new(scionc)
            .args(["--no-prelude", &format!("--emit={emit}")])
            .arg(&src)
            .output()
            .unwrap()
    };
    let lo = run("lo");
    assert!(
        lo.status.success(),
        "{}",
        String::from_utf8_lossy(&lo.stderr)
    );
    assert!(String::from_utf8_lossy(&lo.stdout).contains("\"lo.return\""));
    for emit in ["asm", "llvm", "ptx", "clif"] {
        let o = run(emit);
        let err = String::from_utf8_lossy(&o.stderr);
        // An output this build cannot give is a bad command line for it: status 2.
        assert_eq!(o.status.code(), Some(2), "{emit}: {err}");
        assert!(err.contains("error[E0922]"), "{emit}: {err}");
    }
}
