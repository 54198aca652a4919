#!/usr/bin/env bash
# The price of each effect: step_cost with no effect and with each effect declared alone, run
# interleaved (each round runs every configuration once, in turn, so that they see the same
# machine load). Prints a markdown table: median ns per particle-step over the rounds, the
# marginal cost over no effect, and the world's bytes per particle with its marginal.
#   bash benches/effect_cost.sh [ROUNDS] [step_cost options, e.g. --dim 3]
# Builds target/release/examples/step_cost first. thermal_expansion declares heat conduction
# too, so its marginal includes heat's; axisymmetric is 2D only and is skipped with --dim 3.
set -euo pipefail
rounds=${1:-5}
shift || true
cargo build --release --example step_cost >/dev/null 2>&1
bin=target/release/examples/step_cost
effects=(none damping feedback local_damping damping_zones particle_forces tractions body_force apic heat diffusion
    thermal_expansion axisymmetric)
# The scene's dimension, as step_cost reads it (the last --dim wins; 2 by default).
dim=2
prev=
for a in "$@"; do
    case "$a" in
    --dim=*) dim=${a#--dim=} ;;
    *) [ "$prev" = --dim ] && dim=$a ;;
    esac
    prev=$a
done
if [ "$dim" = 3 ]; then
    kept=()
    for e in "${effects[@]}"; do
        [ "$e" = axisymmetric ] || kept+=("$e")
    done
    effects=("${kept[@]}")
fi
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for _ in $(seq "$rounds"); do
    for e in "${effects[@]}"; do
        line=$("$bin" "$@" --effect "$e" --runs 5 --steps 10 2>/dev/null)
        ns=$(echo "$line" | grep -o '"ns_per_particle_step":[0-9.]*' | cut -d: -f2)
        bytes=$(echo "$line" | grep -o '"bytes_per_particle":[0-9.]*' | cut -d: -f2)
        echo "$e $ns $bytes" >>"$out"
    done
done
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
base_ns=$(awk '$1 == "none" { print $2 }' "$out" | median)
base_b=$(awk '$1 == "none" { print $3; exit }' "$out")
echo "step_cost $* ($rounds interleaved rounds, median of per-round medians)"
echo
echo "| effect | ns per particle-step | marginal ns | bytes per particle | marginal bytes |"
echo "|---|---:|---:|---:|---:|"
for e in "${effects[@]}"; do
    ns=$(awk -v e="$e" '$1 == e { print $2 }' "$out" | median)
    b=$(awk -v e="$e" '$1 == e { print $3; exit }' "$out")
    awk -v e="$e" -v ns="$ns" -v b="$b" -v bn="$base_ns" -v bb="$base_b" \
        'BEGIN { printf "| %s | %.1f | %+.1f | %.1f | %+.1f |\n", e, ns, ns - bn, b, b - bb }'
done
