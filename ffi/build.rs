//! Gives the shared library a soname that carries the ABI's version (`libmpm_gimp.so.0.10`:
//! before 1.0 a minor version may break the ABI), so that hosts linked against one version
//! load no other, and the precision: the `f64` build is `libmpm_gimp_f64.so.0.10`, so that the
//! two libraries can be installed side by side (`ffi/install.sh` installs the matching file
//! and links; cargo itself names both builds `libmpm_gimp.so`).
fn main() {
    let major = env!("CARGO_PKG_VERSION_MAJOR");
    let minor = env!("CARGO_PKG_VERSION_MINOR");
    let name = if std::env::var_os("CARGO_FEATURE_F64").is_some() {
        "mpm_gimp_f64"
    } else {
        "mpm_gimp"
    };
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,lib{name}.so.{major}.{minor}");
    }
}
