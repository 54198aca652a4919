#!/usr/bin/env bash
# Interleaved wall-clock comparison of step_cost binaries on a shared, noisy machine: each
# round runs every binary once, in turn, so that they see the same load; prints, per binary,
# the minimum and the median of the per-round medians (ns per particle-step) and, for every BIN
# after the first, the median of its per-round ratios to the first (the ratio of two runs in the
# same round cancels most of the machine's slow drifts, which the plain medians do not), and
# last whether every BIN ended in the same `state_hash` (the same results).
#   bash benches/compare.sh ROUNDS BIN [BIN ...] -- [step_cost options for every BIN]
# A BIN may carry its own options in one quoted word. E.g.
#   bash benches/compare.sh 5 ./old_step_cost target/release/examples/step_cost -- --dim 2
#   bash benches/compare.sh 5 "target/release/examples/step_cost --simd baseline" \
#       target/release/examples/step_cost -- --dim 3 --order usl
# Thread counts of one build, the same way (`--threads N` steps on a rayon pool of N threads;
# the times are wall time and the state hashes must agree); or `--threads N` after `--` for
# every BIN, e.g. two builds on 2 threads each:
#   bash benches/compare.sh 5 "target/release/examples/step_cost --threads 1" \
#       "target/release/examples/step_cost --threads 2" -- --dim 3
#   bash benches/compare.sh 5 ./old_step_cost target/release/examples/step_cost -- --threads 2
set -euo pipefail
rounds=$1
shift
bins=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
    bins+=("$1")
    shift
done
[ $# -gt 0 ] && shift
out=$(mktemp)
trap 'rm -f "$out"' EXIT
for round in $(seq "$rounds"); do
    for b in "${bins[@]}"; do
        read -ra cmd <<<"$b"
        json=$("${cmd[@]}" "$@" --runs 5 --steps 10 2>/dev/null)
        v=$(echo "$json" | grep -o '"ns_per_particle_step":[0-9.]*' | cut -d: -f2)
        h=$(echo "$json" | grep -o '"state_hash":"[0-9a-f]*"' | cut -d'"' -f4)
        echo "$b|$v|$round|$h" >>"$out"
    done
done
for b in "${bins[@]}"; do
    vals=$(awk -F'|' -v b="$b" '$1 == b { print $2 }' "$out" | sort -g)
    n=$(echo "$vals" | wc -l)
    min=$(echo "$vals" | head -1)
    med=$(echo "$vals" | sed -n "$(( (n + 1) / 2 ))p")
    ratio=""
    if [ "$b" != "${bins[0]}" ]; then
        ratio=$(awk -F'|' -v a="${bins[0]}" -v b="$b" '
            $1 == a { ref[$3] = $2 } $1 == b { val[$3] = $2 }
            END { for (r in val) if (r in ref && ref[r] > 0) print val[r] / ref[r] }' "$out" | sort -g)
        k=$(echo "$ratio" | wc -l)
        ratio="; ratio to the first: median $(echo "$ratio" | sed -n "$(( (k + 1) / 2 ))p" | xargs printf '%.3f')"
    fi
    echo "$b: min $min median $med ns per particle-step over $n rounds ($(echo $vals | tr '\n' ' '))$ratio"
done
hashes=$(cut -d'|' -f4 "$out" | sort -u)
if [ "$(echo "$hashes" | wc -l)" -eq 1 ]; then
    echo "state_hash: $hashes for every BIN and round"
else
    echo "state_hash differs:"
    awk -F'|' '{ print "  " $1 ": " $4 }' "$out" | sort -u
fi
