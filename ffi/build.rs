//! Gives the shared library a soname that carries the ABI's version (`libmpm_gimp.so.0.5`:
//! before 1.0 a minor version may break the ABI), so that hosts linked against one version
//! load no other (`ffi/install.sh` installs the matching file and links).
fn main() {
    let major = env!("CARGO_PKG_VERSION_MAJOR");
    let minor = env!("CARGO_PKG_VERSION_MINOR");
    if std::env::var("CARGO_CFG_TARGET_OS").as_deref() == Ok("linux") {
        println!("cargo:rustc-cdylib-link-arg=-Wl,-soname,libmpm_gimp.so.{major}.{minor}");
    }
}
