#!/usr/bin/env python3
"""The default step against the machine's floors: per particle-step, the bytes the step
moves, the flops and the vector instructions it issues, next to the bandwidth, FMA peak and
vector issue rate measured here, the floor each implies (ns per particle-step) and the
step's measured time (step_cost's median, one worker).

    python3 benches/roofline.py [--trace-shrink 1|2|4|8]

Prints a markdown table (benches/PERFORMANCE.md, "Against the machine's floor"); about a
minute. Needs gcc and objdump; x86-64 with AVX2 and FMA at least. How each figure is had:

- Time: `step_cost --dim D` (131,072 particles in 2D, 262,144 in 3D), median of 7 runs, with
  its reference workload (a fixed scalar loop: it tracks the machine's speed alone). The
  ceilings are measured right before it, each dimension again.
- Instructions and flops: counted, not sampled (this machine's virtual CPU has no hardware
  counters): benches/roofline_trace.c single-steps one whole `World::step_on` call of
  `step_cost --shrink N` (default 8: 2,048 particles in 2D, 512 in 3D; every instruction
  costs a trap, about 20 us here, so the full scene would take minutes), on the instance the
  CPU picks (AVX-512 here), and objdump names each instruction counted. Classes: vector FP
  arithmetic, vector loads, vector stores, other vector instructions (shuffles, blends,
  logic, integer, conversions, mask registers), scalar. Flops: lanes of add, sub, mul, div
  and sqrt once, of a fused multiply-add twice, masked lanes included (an upper bound).
- Vector issue floor: the FP arithmetic instructions over the measured rate of independent
  vector adds and multiplies (roofline_peak.c `issue`), the pipes they must pass through; and,
  as an upper mark, every vector instruction but loads (the load units take those) at the
  same rate, as if shuffles, logic and stores had no pipes of their own.
- Bytes: counted from the columns each pass reads and writes (passes() below, from the
  passes' code: the default uGIMP, MUSL, FLIP, neo-Hookean step), 4 B a value, each column streamed
  once per pass that touches it, a column written but not read costing its read too
  (write-allocate); grid columns once per node of the node box (block cells + 3 per axis)
  per pass. The bandwidth is a triad's (roofline_peak.c), its write-allocate read counted as
  the step's are, over as many bytes as the world has (`bytes_per_particle` x particles): L3
  for the 2D world, memory for the 3D one here.
"""
import json
import math
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BIN = ROOT / "target/release"
STEP = BIN / "examples/step_cost"

# Per pass: particle columns read, written (columns of D, D*D or NS values, or 1), and grid
# node columns read, written, for the default step (MUSL: src/world/step.rs's phase order).
# "w_only" are written without being read (x_start, tau): write-allocate reads them too.
def passes(d):
    ns = 4 if d == 2 else 6
    return {
        # mass, momentum, force from x, v, mass, tau/rho0 (p2g::scatter_rows)
        "scatter": dict(r=2 * d + 1 + ns, w=0, w_only=0, gr=1 + 2 * d, gw=1 + 2 * d),
        # x, x_low, v updated, x_start kept, status; mass for the re-map (g2p::particles),
        # which gathers v and a and adds the re-mapped momenta to the grid
        "particles": dict(r=3 * d + 2, w=4 * d, w_only=d, gr=2 * d + d, gw=d),
        # H and tau/rho0 from the re-mapped velocities at x_start (stress::stress)
        "stress": dict(r=d + d * d + 2, w=d * d + ns, w_only=ns, gr=d, gw=0),
        # grid passes on the node box: reset, velocity, acceleration, re-map velocity
        "grid": dict(r=0, w=0, w_only=0, gr=(1 + d) + (1 + 2 * d) + (1 + d),
                     gw=(1 + 3 * d) + d + 2 * d + d),
    }


def run(cmd, **kw):
    return subprocess.run(cmd, check=True, capture_output=True, text=True, **kw).stdout


def build():
    run(["cargo", "build", "--release", "--example", "step_cost"], cwd=ROOT)
    run(["gcc", "-O2", "-o", BIN / "roofline_trace", ROOT / "benches/roofline_trace.c"])
    run(["gcc", "-O3", "-march=native", "-o", BIN / "roofline_peak",
         ROOT / "benches/roofline_peak.c"])


def step_cost(*args):
    return json.loads(run([STEP, *args]).splitlines()[-1])


def disassembly():
    """Address -> (mnemonic, operands) of every instruction of step_cost."""
    code = {}
    line = re.compile(r"^\s*([0-9a-f]+):\t(\S+)\s*(.*)$")
    for text in run(["objdump", "-d", "--no-show-raw-insn", STEP]).splitlines():
        m = line.match(text)
        if m:
            code[int(m.group(1), 16)] = (m.group(2), m.group(3).split("#")[0].strip())
    return code


def operands(ops):
    """AT&T operands, split at the commas outside parentheses and braces."""
    out, depth, cur = [], 0, ""
    for c in ops:
        depth += c in "({"
        depth -= c in ")}"
        if c == "," and depth == 0:
            out.append(cur)
            cur = ""
        else:
            cur += c
    return out + [cur] if cur else out


FP = re.compile(r"^v?(add|sub|mul|div|sqrt|min|max|cmp\w*|rcp\w*|rsqrt\w*|round|rndscale|"
                r"fn?m(?:add|sub)\d{3}|fmaddsub\d{3}|fmsubadd\d{3}|getexp|getmant|scalef)"
                r"(ps|pd|ss|sd)$")
FLOPS = {"add": 1, "sub": 1, "mul": 1, "div": 1, "sqrt": 1}


def classify(mnemonic, ops):
    """(class, flops) of one instruction."""
    width = 512 if "%zmm" in ops else 256 if "%ymm" in ops else 128 if "%xmm" in ops else 0
    if not width and not re.match(r"^k[a-z]", mnemonic):
        return "scalar", 0
    parts = operands(ops)
    fp = FP.match(mnemonic)
    if fp:
        kind, suffix = fp.group(1), fp.group(2)
        lanes = 1 if suffix[0] == "s" else width // (32 if suffix[1] == "s" else 64)
        per = 2 if kind.startswith(("fm", "fnm")) else FLOPS.get(kind, 0)
        return "arith", per * lanes
    if re.match(r"^v?(mov|broadcast|pbroadcast)", mnemonic) and parts:
        if "(" in parts[-1]:
            return "store", 0
        if any("(" in p for p in parts[:-1]):
            return "load", 0
    return "other", 0


def trace(dim, shrink, code, offset):
    """Instructions per class and flops per particle-step of one traced step."""
    args = ["--dim", str(dim), "--shrink", str(shrink), "--runs", "5", "--steps", "1"]
    # step_cost takes 3 untimed steps first: the 4th call is its first timed step.
    lines = run([BIN / "roofline_trace", f"{offset:x}", "4", STEP, *args]).splitlines()
    counts = {"arith": 0, "load": 0, "store": 0, "other": 0, "scalar": 0}
    flops = 0
    for line in lines:
        if line.startswith("{"):
            particles = json.loads(line)["particles"]
            continue
        f = line.split()
        if f[0] == "-":  # outside step_cost (a libc call): counted as scalar
            counts["scalar"] += int(f[2])
            continue
        n = int(f[1])
        cls, fl = classify(*code.get(int(f[0], 16), ("?", "")))
        counts[cls] += n
        flops += fl * n
    return {k: v / particles for k, v in counts.items()}, flops / particles, particles


def peak(*args):
    return float(run([BIN / "roofline_peak", *args]))


def main():
    shrink = "8"
    if len(sys.argv) == 3 and sys.argv[1] == "--trace-shrink" and sys.argv[2] in ("1", "2", "4", "8"):
        shrink = sys.argv[2]
    elif len(sys.argv) != 1:
        sys.exit("usage: python3 benches/roofline.py [--trace-shrink 1|2|4|8]")
    build()
    code = disassembly()
    nm = run(["nm", "-C", STEP])
    offset = int(re.search(r"^([0-9a-f]+) T .*World>::step_on$", nm, re.M).group(1), 16)
    col = {}
    for dim in (2, 3):
        cls, flops, traced = trace(dim, int(shrink), code, offset)
        # The ceilings right before the step's timing: this machine's speed moves by the
        # minute (its FMA peak measured 180 and 273 GFLOP/s ten minutes apart).
        fma, issue = peak("fma"), peak("issue")
        timed = step_cost("--dim", str(dim))
        n = timed["particles"]
        nodes = math.prod(c + 3 for c in timed["cells"]) / n
        table = passes(dim).values()
        particle_b = 4 * sum(p["r"] + p["w"] + p["w_only"] for p in table)
        grid_b = 4 * nodes * sum(p["gr"] + p["gw"] for p in table)
        gbs = peak("triad", str(int(timed["bytes_per_particle"] * n)))
        floors = {
            "bandwidth": (particle_b + grid_b) / gbs,
            "flops": flops / fma,
            "issue": cls["arith"] / issue,
        }
        every = (cls["arith"] + cls["other"] + cls["store"]) / issue
        col[dim] = [
            f"{timed['simd']}, {n:,} ({traced:,} traced)",
            f"{timed['ns_per_particle_step']:.2f}",
            f"{timed['reference_ns']:.2f}",
            f"{particle_b + grid_b:.0f} ({particle_b} + {grid_b:.0f})",
            f"{gbs:.1f}",
            f"{floors['bandwidth']:.2f}",
            f"{flops:.0f}",
            f"{fma:.0f}",
            f"{floors['flops']:.2f}",
            f"{sum(cls.values()):.0f}",
            " / ".join(f"{cls[k]:.0f}" for k in ("arith", "load", "store", "other", "scalar")),
            f"{issue:.2f}",
            f"{floors['issue']:.2f} / {every:.2f}",
            f"{timed['ns_per_particle_step'] / max(floors.values()):.2f}",
        ]
    names = [
        "instance, particles",
        "step, measured (ns, median of 7 runs)",
        "step_cost's reference workload (ns per particle; the machine's speed)",
        "bytes moved (particle columns + grid)",
        "bandwidth at the world's size (triad, GB/s)",
        "bandwidth floor (ns)",
        "flops (add, sub, mul, div, sqrt; FMA twice)",
        "FMA peak (GFLOP/s, one core)",
        "flop floor (ns)",
        "instructions retired",
        "of them FP arithmetic / loads / stores / other vector / scalar",
        "vector add and multiply rate (instructions per ns, one core)",
        "vector issue floor (ns): FP arithmetic alone / every vector instruction but loads",
        "step over its highest floor (bandwidth, flops, FP arithmetic issue)",
    ]
    print("| per particle-step | 2D | 3D |\n|---|---:|---:|")
    for k, name in enumerate(names):
        print(f"| {name} | {col[2][k]} | {col[3][k]} |")


if __name__ == "__main__":
    main()
