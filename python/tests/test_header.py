"""The package's C declarations are the header's: the generated _header.py and the stubs
_types.pyi are current (as ffi/tests/header.rs checks the header against ffi/src), the
installed package holds them, and the libraries are the header's ABI."""

import importlib.util
from pathlib import Path

import mpm_gimp
from mpm_gimp import _header

PYTHON = Path(__file__).resolve().parents[1]


def test_the_generated_declarations_are_the_headers():
    spec = importlib.util.spec_from_file_location("gen_header", PYTHON / "gen_header.py")
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    fresh = gen.generate()
    committed = (PYTHON / "mpm_gimp" / "_header.py").read_text()
    assert fresh == committed, "stale: run python3 python/gen_header.py"
    installed = Path(_header.__file__).read_text()
    assert installed == committed, "the installed package is older: pip install ./python"
    assert gen.stubs() == (PYTHON / "mpm_gimp" / "_types.pyi").read_text(), "stale stubs"


def test_the_libraries_are_the_headers_abi():
    version = _header.CONSTANTS["MPM_GIMP_ABI_VERSION"]
    assert mpm_gimp._precision.lib.mpm_abi_version() == version
    assert mpm_gimp.f64._precision.lib.mpm_abi_version() == version
    # Each library is its own precision: its defaults carry that precision's cookie.
    assert mpm_gimp.WorldDef().internal_cookie != mpm_gimp.f64.WorldDef().internal_cookie
