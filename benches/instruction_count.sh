#!/usr/bin/env bash
# Instructions per particle-step inside World::step, counted by callgrind: deterministic for a
# given binary, unlike wall-clock time on a shared machine. Arguments go to step_cost, e.g.
#   bash benches/instruction_count.sh --dim 2 --order usl
# Counts the baseline (SSE2) instance of the step: valgrind 3.19 cannot decode every AVX
# instruction of the AVX2 instance. Needs valgrind (apt-get install valgrind).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --example step_cost >/dev/null 2>&1
out=$(mktemp)
trap 'rm -f "$out"' EXIT
steps=1
runs=5
warmup=3
valgrind --tool=callgrind --callgrind-out-file="$out" \
    ./target/release/examples/step_cost "$@" --simd baseline --runs "$runs" --steps "$steps" >/dev/null 2>&1
total=$(callgrind_annotate --inclusive=yes "$out" 2>/dev/null \
    | grep -E "World::step_with_simd \[" | head -1 | awk '{gsub(",", "", $1); print $1}')
particles=$(./target/release/examples/step_cost "$@" --runs 5 --steps 1 2>/dev/null \
    | grep -o '"particles":[0-9]*' | cut -d: -f2)
echo "$* : $(( total / ((warmup + runs * steps) * particles) )) instructions per particle-step"
