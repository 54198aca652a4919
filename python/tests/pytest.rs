//! The Python package's pytest suite (python/tests), run by `cargo test`: with the Python that
//! `MPM_PYTHON` names, in which the package is installed (`pip install ./python pytest
//! hypothesis`). Without `MPM_PYTHON` the test is skipped with a note, unless
//! `MPM_REQUIRE_PYTHON` is set (as `.ci/run` does), which makes a missing Python a failure.

use std::path::Path;
use std::process::Command;

#[test]
fn the_python_package_passes_its_pytest_suite() {
    let Some(python) = std::env::var_os("MPM_PYTHON") else {
        assert!(
            std::env::var_os("MPM_REQUIRE_PYTHON").is_none(),
            "MPM_REQUIRE_PYTHON is set but MPM_PYTHON names no Python"
        );
        eprintln!(
            "skipped: set MPM_PYTHON to a Python with the package installed \
             (python3 -m venv v && v/bin/pip install ./python pytest hypothesis)"
        );
        return;
    };
    let tests = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    // From the tests' directory, so that `import mpm_gimp` finds the installed package, not
    // the source tree (which holds no native library).
    let status = Command::new(&python)
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .arg(&tests)
        .current_dir(&tests)
        .status()
        .expect("MPM_PYTHON runs");
    assert!(status.success(), "pytest failed: {status}");
}
