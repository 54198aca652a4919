//! Building and running C and C++ programs against the library, for the tests that check the
//! C interface from C.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The crate's folder (`ffi/`).
pub fn ffi_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The static library cargo built with this test (it sits beside the test binary, since the
/// library target is built with every crate type for the tests).
pub fn static_lib() -> PathBuf {
    let exe = std::env::current_exe().expect("test binary path");
    let lib = exe.parent().expect("deps folder").join("libmpm_gimp.a");
    assert!(lib.exists(), "{} not built", lib.display());
    lib
}

/// Whether the library and tests are built for double precision.
pub const F64: bool = cfg!(feature = "f64");

/// The source language of a host.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Lang {
    /// C99, compiled with gcc.
    C99,
    /// C++17, compiled with g++.
    Cpp17,
}

/// Warnings that fail a host's build.
pub const STRICT: &[&str] = &["-Wall", "-Wextra", "-Werror", "-pedantic"];
/// The sanitizers hosts are also built with.
pub const SANITIZE: &[&str] = &["-fsanitize=address,undefined", "-fno-sanitize-recover=all"];

/// Compiles `sources` (paths relative to `ffi/`) into an executable named `name` in a
/// temporary folder, against the header and the static library, with `flags`. Panics with the
/// compiler's output if it fails.
pub fn build(name: &str, lang: Lang, sources: &[&str], flags: &[&str]) -> PathBuf {
    let dir = ffi_dir();
    let out_dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("c-hosts");
    std::fs::create_dir_all(&out_dir).expect("temporary folder");
    let suffix = if F64 { "-f64" } else { "" };
    let exe = out_dir.join(format!("{name}{suffix}"));
    let (compiler, std) = match lang {
        Lang::C99 => ("gcc", "-std=c99"),
        Lang::Cpp17 => ("g++", "-std=c++17"),
    };
    let mut cmd = Command::new(compiler);
    cmd.arg(std).arg("-O1").arg("-g");
    cmd.args(flags);
    if F64 {
        cmd.arg("-DMPM_GIMP_F64");
    }
    cmd.arg("-I").arg(dir.join("include"));
    for s in sources {
        cmd.arg(dir.join(s));
    }
    cmd.arg(static_lib());
    cmd.args(["-lpthread", "-ldl", "-lm"]);
    cmd.arg("-o").arg(&exe);
    let out = cmd
        .output()
        .unwrap_or_else(|e| panic!("{compiler} not runnable: {e}"));
    assert!(
        out.status.success(),
        "{compiler} failed on {sources:?}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    exe
}

/// Runs `exe` with `args`; panics with its output unless it exits with 0.
pub fn run(exe: &Path, args: &[&str]) -> Output {
    let out = Command::new(exe)
        .args(args)
        .output()
        .unwrap_or_else(|e| panic!("{} not runnable: {e}", exe.display()));
    assert!(
        out.status.success(),
        "{} failed ({}):\nstdout:\n{}\nstderr:\n{}",
        exe.display(),
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}
