"""The examples in python/examples run (briefly) and say what they should."""

import subprocess
import sys
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def run(name, *args):
    done = subprocess.run(
        [sys.executable, str(EXAMPLES / name), *args], capture_output=True, text=True, timeout=300
    )
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_drop_runs():
    out = run("drop.py", "--frames", "20")
    assert "frozen 0" in out and "lowest y" in out


def test_the_convergence_study_finds_first_order():
    """uGIMP's bar converges at first order in h (the Rust tests' refinement test)."""
    out = run("convergence.py", "--cells", "8", "16")
    order = float(out.splitlines()[-1].split()[-1])
    assert 0.8 < order < 1.2, out
