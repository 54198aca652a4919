//! Precision cannot be mixed silently: a host compiled for the other precision than the
//! library's fails to link (the header maps the default functions to precision-specific
//! symbols), and one compiled for the library's precision links and runs.

mod common;

use common::{ffi_dir, static_lib, F64};
use std::process::Command;

/// Compiles and links a host that needs a world definition, with or without MPM_GIMP_F64.
fn link(define_f64: bool) -> std::process::Output {
    let src = ffi_dir().join("tests/c/precision.c");
    let exe = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("precision-{}-{}", F64, define_f64));
    let mut cmd = Command::new("gcc");
    cmd.args(["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]);
    if define_f64 {
        cmd.arg("-DMPM_GIMP_F64");
    }
    cmd.arg("-I")
        .arg(ffi_dir().join("include"))
        .arg(&src)
        .arg(static_lib())
        .args(["-lpthread", "-ldl", "-lm", "-o"])
        .arg(&exe);
    let out = cmd.output().expect("gcc runs");
    if out.status.success() {
        common::run(&exe, &[]);
    }
    out
}

#[test]
fn a_host_of_the_library_precision_links_and_runs() {
    let out = link(F64);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_host_of_the_other_precision_does_not_link() {
    let out = link(!F64);
    assert!(
        !out.status.success(),
        "a host of the other precision linked"
    );
    let missing = if F64 {
        "mpm_world_def_default_f32"
    } else {
        "mpm_world_def_default_f64"
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(missing),
        "the link failed for another reason than the precision symbol:\n{stderr}"
    );
}
