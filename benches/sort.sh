#!/usr/bin/env bash
# The reorder by cell (`World::sort_particles`) on a mixed scene: step_cost's scene in fill
# order, shuffled (`--particle-order shuffled`, a fixed random permutation), shuffled then
# sorted once (`--sort on`), and in fill order sorted, run interleaved (each round runs every
# configuration once, in turn, so that they see the same machine load), 2D and 3D. Prints a
# markdown table: the median over the rounds of the ns per particle-step, each with the median
# of its per-round ratios to fill order, and the sort call's own cost in ns per particle.
#   bash benches/sort.sh [ROUNDS] [step_cost options, e.g. --material fluid]
# Builds target/release/examples/step_cost first.
set -euo pipefail
rounds=${1:-5}
shift || true
cargo build --release --example step_cost >/dev/null 2>&1
bin=target/release/examples/step_cost
cases=("fill off" "shuffled off" "shuffled on" "fill on")
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for round in $(seq "$rounds"); do
    for dim in 2 3; do
        for c in "${cases[@]}"; do
            read -r order sort <<<"$c"
            line=$("$bin" "$@" --dim "$dim" --particle-order "$order" --sort "$sort" \
                --runs 5 --steps 10 2>/dev/null)
            ns=$(echo "$line" | grep -o '"ns_per_particle_step":[0-9.]*' | cut -d: -f2)
            sort_ns=$(echo "$line" | grep -o '"sort_ns_per_particle":[0-9.]*' | cut -d: -f2)
            echo "$dim $order-$sort $round $ns $sort_ns" >>"$out"
        done
    done
done
median() { sort -g | awk '{ v[NR] = $1 } END { print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'; }
echo "step_cost $* ($rounds interleaved rounds, median of per-round medians; (ratio to fill order))"
echo
echo "| particle order | 2D ns | 2D sort ns per particle | 3D ns | 3D sort ns per particle |"
echo "|---|---:|---:|---:|---:|"
for c in "${cases[@]}"; do
    read -r order sort <<<"$c"
    row="| $order, sort $sort"
    for dim in 2 3; do
        ns=$(awk -v d="$dim" -v k="$order-$sort" '$1 == d && $2 == k { print $4 }' "$out" | median)
        ratio=$(awk -v d="$dim" -v k="$order-$sort" '
            $1 == d && $2 == "fill-off" { base[$3] = $4 }
            $1 == d && $2 == k { v[$3] = $4 }
            END { for (r in v) print v[r] / base[r] }' "$out" | median)
        s=$(awk -v d="$dim" -v k="$order-$sort" '$1 == d && $2 == k { print $5 }' "$out" | median)
        [ "$sort" = off ] && s=
        row="$row | $(printf '%.2f (%.3f)' "$ns" "$ratio") | ${s:+$(printf '%.2f' "$s")}"
    done
    echo "$row |"
done
