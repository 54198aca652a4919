#!/usr/bin/env python3
"""The build's budgets, checked on the release build CI has just made (not a timed test):

- the functions compiled per instance of the particle passes and chunk kernels
  (`benches/compiled_forms.sh`): what multiplies the build when a type parameter or a form is
  added, so a new one must raise the budget here, with its measured price in
  benches/PERFORMANCE.md ("Compiled forms");
- the size of the kernel's release library (its object code grows with every compiled form);
- the size of README.md and ARCHITECTURE.md: a user's guide and a map, not a history;
- the wall time cargo took for the kernel's library in that build (`--timings`) over the
  time it took for all the dependencies in the same build: a ratio, so that a slow or busy
  machine, which slows both, does not fail it, and a form or an inlining that multiplies the
  kernel's build does.

Run from the repository root after `cargo test --release --workspace --exclude mpm-gimp-mpi
--no-run --timings` (CI's test build): python3 .ci/budgets.py"""
import glob
import json
import os
import subprocess
import sys

# Ceilings. Functions per instance as compiled in the f32 build (146, 146 and 119 at the
# commit that set them), the library's bytes (11.8 MB then) and the kernel library's wall time
# in CI's test build (its clean build alone took about 60 s). The library's ceiling rose to
# 13.2 MB with the parallel step (13.03 MB: its tiles, slabs and scans per form), and to
# 13.4 MB with heat and diffusion in parallel (13.10 to 13.28 MB: their loops one call each
# that a tile or a range makes, and the tiles' clip), and to 13.8 MB with colliders (13.48 MB:
# 0.13 MB of it the library's metadata for their API, 0.04 MB code, one copy per dimension;
# 13.60 MB with walls that move and distance fields), and to 14.3 MB with MUSL's particle
# pass by tiles (13.71 to 14.18 MB: the re-map of the groups a tile reads, one function per
# form, 9 per instance, 0.07 MB; the tiled pass and its cut, 0.08 MB; the rest the objects'
# tables and the metadata; 2 workers went from 0.59-0.61 to 0.54 of one worker's time), and
# to 14.5 MB with a particle's whole state read and written, a collider's speed in the
# substep plan and its contact modes (14.31 MB, no compiled form added: 155/155/128), and
# to 14.9 MB with the fluids' volume relaxation (14.39 to 14.82 MB: its scatter and gather
# one function per form, 0.13 MB of code with their calls per instance, and their metadata;
# compiled into every instance's transport pass they took it to 14.97 MB, and in the
# baseline instance alone, 14.71 MB, a fluid's step took 1.88 times as long, not 1.65),
# and to 15.1 MB with XPIC(k) and FMPM(k) (14.80 to 15.05 MB, no compiled form added:
# 155/155/128; 0.04 MB of object code, `Columns::project` one function per form and instance
# and the node passes per dimension, the rest the crate's metadata of the new generic code),
# and to 15.3 MB with follower tractions, traction ids that stay, the point families' faces
# integrated and the body force affine in position (14.80 to 14.95 MB on their own, 15.15 MB
# with XPIC; no compiled form added: the traction pass was one function per form already).
# The kernel's build time was a ceiling of 240 s until a CI machine two to three times as slow
# as usual built it in 264 s with nothing changed; in a build where another build ran beside
# it, the kernel took 570 s and its dependencies 380 s (1.5).
FUNCTIONS = {"avx2": 155, "avx512": 155, "baseline": 128}
LIBRARY_BYTES = 15_300_000
KERNEL_BUILD_OVER_DEPENDENCIES = 2.0
# README.md is a user's guide and ARCHITECTURE.md a map; figures and their history live in
# benches/PERFORMANCE.md.
DOC_BYTES = {"README.md": 12_000, "ARCHITECTURE.md": 12_000}

failed = []
libs = sorted(glob.glob("target/release/deps/libmpm_gimp-*.rlib"), key=os.path.getmtime)
if not libs:
    sys.exit("no kernel library in target/release/deps: build first")
lib = libs[-1]

counts = subprocess.run(
    ["bash", "benches/compiled_forms.sh", lib], check=True, capture_output=True, text=True
).stdout
print(counts, end="")
for line in counts.splitlines():
    instance = line.split()[0]
    total = int(line.rsplit("(", 1)[1].split()[0])
    ceiling = FUNCTIONS.get(instance)
    if ceiling is None or total > ceiling:
        failed.append(f"{instance}: {total} functions, budget {ceiling}")
for instance in FUNCTIONS:
    if instance not in counts:
        print(f"{instance}: not compiled in this build")

size = os.path.getsize(lib)
print(f"kernel library {size} bytes (budget {LIBRARY_BYTES})")
if size > LIBRARY_BYTES:
    failed.append(f"library {size} bytes, budget {LIBRARY_BYTES}")

for doc, ceiling in DOC_BYTES.items():
    size = os.path.getsize(doc)
    print(f"{doc} {size} bytes (budget {ceiling})")
    if size > ceiling:
        failed.append(f"{doc} {size} bytes, budget {ceiling}")

report = "target/cargo-timings/cargo-timing.html"
if os.path.exists(report):
    text = open(report).read()
    start = text.index("UNIT_DATA = ") + len("UNIT_DATA = ")
    units, _ = json.JSONDecoder().raw_decode(text[start:])
    # The workspace's own crates, as cargo lists them; every other unit is a dependency.
    metadata = subprocess.run(
        ["cargo", "metadata", "--no-deps", "--format-version", "1"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    workspace = {p["name"] for p in json.loads(metadata)["packages"]}
    kernel = [
        u["duration"]
        for u in units
        if u["name"] == "mpm-gimp" and u["target"] == "" and u["mode"] == "todo"
    ]
    dependencies = sum(u["duration"] for u in units if u["name"] not in workspace)
    if kernel and dependencies > 0:
        seconds = max(kernel)
        ratio = seconds / dependencies
        print(
            f"kernel library built in {seconds:.1f} s, its dependencies in {dependencies:.1f} s: "
            f"{ratio:.2f} (budget {KERNEL_BUILD_OVER_DEPENDENCIES:.2f})"
        )
        if ratio > KERNEL_BUILD_OVER_DEPENDENCIES:
            failed.append(
                f"kernel build {ratio:.2f} of its dependencies', "
                f"budget {KERNEL_BUILD_OVER_DEPENDENCIES:.2f}"
            )
    else:
        print("the timing report has no kernel library or no dependency unit (nothing rebuilt)")
else:
    print("no timing report: the build time is not checked")

if failed:
    sys.exit("over budget: " + "; ".join(failed))
