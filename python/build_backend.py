"""The package's PEP 517 build backend: `pip install ./python` from a clone of the repository.

It builds the native library (this directory's crate, mpm-gimp-python) twice with cargo,
single precision into the workspace's target directory (`CARGO_TARGET_DIR`, else target/) and
double precision (`--features f64`) into its f64/ subdirectory, as the repository's CI does,
so a workspace that was built already only links; then it writes a wheel holding the Python
package and both libraries (`_native_f32.so`, `_native_f64.so`). The wheel's tag is
`py3-none-<platform>`: the libraries do not link libpython (ctypes loads them). Nothing is
downloaded here; numpy, the one dependency, comes from pip.

`-p mpm-gimp` in the cargo command: it builds the kernel with the features the workspace's
`cargo test` gives it (its default `std`), so that the kernel compiled there is reused here.
"""

import base64
import hashlib
import os
import platform
import re
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PACKAGE = "mpm_gimp"


def _version():
    text = (HERE / "Cargo.toml").read_text()
    return re.search(r'^version = "([^"]+)"', text, re.M).group(1)


def _project():
    with open(HERE / "pyproject.toml", "rb") as f:
        return tomllib.load(f)["project"]


def _metadata():
    p = _project()
    lines = [
        "Metadata-Version: 2.1",
        f"Name: {p['name']}",
        f"Version: {_version()}",
        f"Summary: {p['description']}",
        f"License: {p['license']['text']}",
        f"Requires-Python: {p['requires-python']}",
    ]
    lines += [f"Requires-Dist: {d}" for d in p["dependencies"]]
    readme = HERE / p["readme"]
    lines += ["Description-Content-Type: text/markdown", "", readme.read_text()]
    return "\n".join(lines)


def _tag():
    machine = platform.machine().lower()
    return f"py3-none-{sys.platform}_{machine}"


def _cargo(target_dir, features):
    cargo = shutil.which("cargo") or str(Path.home() / ".cargo" / "bin" / "cargo")
    command = [cargo, "build", "--release", "-p", "mpm-gimp", "-p", "mpm-gimp-python", "--lib"]
    command += features
    env = dict(os.environ, CARGO_TARGET_DIR=str(target_dir))
    print("+", " ".join(command), f"(CARGO_TARGET_DIR={target_dir})", file=sys.stderr)
    subprocess.run(command, cwd=ROOT, env=env, check=True, stdout=sys.stderr)
    return Path(target_dir) / "release" / "libmpm_gimp_python.so"


def _libraries():
    if not (ROOT / "ffi" / "include" / "mpm_gimp.h").is_file():
        raise RuntimeError(
            "mpm_gimp builds from a clone of the mpm-gimp repository (pip install ./python)"
        )
    target = Path(os.environ.get("CARGO_TARGET_DIR") or ROOT / "target")
    if not target.is_absolute():
        target = ROOT / target
    return {
        "_native_f32.so": _cargo(target, []),
        "_native_f64.so": _cargo(target / "f64", ["--features", "f64"]),
    }


def _record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def get_requires_for_build_wheel(config_settings=None):
    return []


def _wheel_text():
    lines = ["Wheel-Version: 1.0", "Generator: mpm-gimp build_backend", "Root-Is-Purelib: false"]
    return "\n".join(lines + [f"Tag: {_tag()}"]) + "\n"


def prepare_metadata_for_build_wheel(metadata_directory, config_settings=None):
    """The metadata alone, without a build (pip asks for it first)."""
    info = Path(metadata_directory) / f"mpm_gimp-{_version()}.dist-info"
    info.mkdir(parents=True, exist_ok=True)
    (info / "METADATA").write_text(_metadata())
    (info / "WHEEL").write_text(_wheel_text())
    return info.name


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    version = _version()
    files = {}
    for path in sorted((HERE / PACKAGE).iterdir()):
        if path.suffix in (".py", ".pyi", ".typed"):
            files[f"{PACKAGE}/{path.name}"] = path.read_bytes()
    for name, path in _libraries().items():
        files[f"{PACKAGE}/{name}"] = path.read_bytes()
    info = f"mpm_gimp-{version}.dist-info"
    files[f"{info}/METADATA"] = _metadata().encode()
    files[f"{info}/WHEEL"] = _wheel_text().encode()
    record = [_record_line(n, d) for n, d in files.items()] + [f"{info}/RECORD,,"]
    files[f"{info}/RECORD"] = ("\n".join(record) + "\n").encode()
    name = f"mpm_gimp-{version}-{_tag()}.whl"
    with zipfile.ZipFile(Path(wheel_directory) / name, "w", zipfile.ZIP_DEFLATED) as z:
        for n, d in files.items():
            info_ = zipfile.ZipInfo(n, date_time=(1980, 1, 1, 0, 0, 0))
            info_.external_attr = (0o755 if n.endswith(".so") else 0o644) << 16
            info_.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info_, d)
    return name
