#!/usr/bin/env bash
# Instructions per particle-step inside World::step, counted by callgrind: deterministic for a
# given binary, unlike wall-clock time on a shared machine. Arguments go to step_cost, e.g.
#   bash benches/instruction_count.sh --dim 2 --order usl
#   bash benches/instruction_count.sh --dim 2 --simd avx2
# Prints the step's total and its three particle passes. Counts the baseline (SSE2) instance
# unless `--simd avx2` asks for the AVX2 instance (where present): valgrind 3.19 decodes no
# AVX-512 (`--simd auto` on such a CPU) and not every AVX instruction the compiler emits (the
# register form of VEX vmovq, 66 0F D6, in some 3D passes), and then stops with an illegal
# instruction.
# Needs valgrind (apt-get install valgrind).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --example step_cost >/dev/null 2>&1
out=$(mktemp)
json=$(mktemp)
trap 'rm -f "$out" "$json"' EXIT
steps=1
runs=5
# step_cost's untimed warm-up steps, which callgrind counts too.
warmup=3
if ! valgrind --tool=callgrind --callgrind-out-file="$out" \
    ./target/release/examples/step_cost --simd baseline "$@" --runs "$runs" --steps "$steps" \
    >"$json" 2>/dev/null; then
    echo "$*: step_cost did not finish under valgrind (with --simd avx2, try --simd baseline)" >&2
    exit 1
fi
particles=$(grep -o '"particles":[0-9]*' "$json" | cut -d: -f2)
simd=$(grep -o '"simd":"[a-z0-9]*"' "$json" | cut -d'"' -f4)
per_step=$(( (warmup + runs * steps) * particles ))
annotated=$(callgrind_annotate --inclusive=yes "$out" 2>/dev/null)
# Inclusive count of the first function whose name matches $1, per particle-step.
count() {
    local n
    n=$(echo "$annotated" | grep -E "$1( \[.*)?\$" | head -1 | awk '{gsub(",", "", $1); print $1}')
    echo $(( ${n:-0} / per_step ))
}
isa='(passes::avx2|passes::avx512|Baseline as mpm_gimp::world::passes::Passes>)'
echo "$* (${simd} instance): $(count 'World>::step_on') instructions per particle-step;" \
    "scatter $(count "${isa}::scatter"), particle pass $(count "${isa}::particles")," \
    "stress pass $(count "${isa}::stress")"
