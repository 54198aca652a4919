//! `include/mpm_gimp.h` is what cbindgen makes of this crate: the test regenerates it and fails
//! when the committed header differs. `UPDATE_HEADER=1` rewrites it instead.

use std::path::Path;

/// The header as cbindgen generates it now, with the version macros from Cargo.toml.
fn generate() -> String {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut config = cbindgen::Config::from_file(dir.join("cbindgen.toml")).expect("cbindgen.toml");
    let precision = config.after_includes.take().unwrap_or_default();
    config.after_includes = Some(format!(
        "{precision}\n\n/* The version of this header, from the crate version. */\n\
         #define MPM_GIMP_VERSION \"{v}\"\n\
         /* major * 10000 + minor * 100 + patch; compare with mpm_abi_version(). */\n\
         #define MPM_GIMP_ABI_VERSION {abi}\n",
        v = env!("CARGO_PKG_VERSION"),
        abi = mpm_gimp::ABI_VERSION,
    ));
    let mut out = Vec::new();
    cbindgen::Builder::new()
        .with_crate(dir)
        .with_config(config)
        .generate()
        .expect("cbindgen generates the header")
        .write(&mut out);
    function_types(&String::from_utf8(out).expect("the header is UTF-8"))
}

/// The callback types the header declares as function types, used through pointers, as Box2D
/// v3 declares its task callbacks (`typedef void MpmTaskCallback(...);` and
/// `MpmTaskCallback *task`), so that a host's callback is declared with the type's own name.
/// cbindgen writes a Rust `fn` type as a pointer typedef (`typedef void (*MpmTaskCallback)(...)`
/// and `MpmTaskCallback task`): the same type in C, which [`function_types`] respells.
const FUNCTION_TYPES: [&str; 3] = [
    "MpmTaskCallback",
    "MpmEnqueueTaskCallback",
    "MpmFinishTaskCallback",
];

/// `header` with each of [`FUNCTION_TYPES`] declared as a function type and used as a pointer
/// to it, outside comments; the arguments of a typedef that runs over several lines stay
/// aligned under its first.
fn function_types(header: &str) -> String {
    let mut out = String::with_capacity(header.len() + 64);
    // Columns the continuation lines of the typedef being rewritten move left by.
    let mut shift = 0;
    for line in header.lines() {
        let mut l = line.to_string();
        if !l.trim_start().starts_with("//") {
            if shift > 0 {
                l = l.replacen(&" ".repeat(shift), "", 1);
            }
            if l.ends_with(';') {
                shift = 0;
            }
            for name in FUNCTION_TYPES {
                let pointer = format!("(*{name})(");
                if l.contains(&pointer) {
                    l = l.replace(&pointer, &format!("{name}("));
                    if !l.ends_with(';') {
                        shift = "(*)".len();
                    }
                }
                l = l.replace(&format!("{name} "), &format!("{name} *"));
            }
        }
        out.push_str(&l);
        out.push('\n');
    }
    out
}

#[test]
fn committed_header_is_current() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("include/mpm_gimp.h");
    let fresh = generate();
    if std::env::var_os("UPDATE_HEADER").is_some() {
        std::fs::write(&path, &fresh).expect("write the header");
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == fresh,
        "{} is stale: run UPDATE_HEADER=1 cargo test -p mpm-gimp-ffi --test header",
        path.display()
    );
}
