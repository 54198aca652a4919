#!/usr/bin/env bash
# The functions the release kernel library defines for each particle pass and chunk kernel,
# per instruction set (`nm`). A form is one (dimension form, stencil width) in one
# instruction set, 9 per instruction set; everything else a step is configured with is a
# value, except the scatter's row configuration (5 functions per form: USL/MUSL and USF's two
# scatters, FLIP or APIC; 2 in the baseline instance, compiled for size), the gather's kind (5
# per form) and the re-map scatter's transfer (2 per form): see ARCHITECTURE.md, "Decisions".
# `remap` is MUSL's re-map of the particles another tile of the parallel step updated.
# The materials' stress (`kirchhoff`) is a chunk kernel per dimension, not per form.
#   bash benches/compiled_forms.sh            # builds the release library first
#   bash benches/compiled_forms.sh LIB.rlib   # counts in an existing library
set -euo pipefail
cd "$(dirname "$0")/.."
lib=${1:-}
if [ -z "$lib" ]; then
    cargo build --release -p mpm-gimp >/dev/null 2>&1
    lib=$(ls -t target/release/deps/libmpm_gimp-*.rlib | head -1)
fi
nm -C --defined-only "$lib" 2>/dev/null |
    sed -nE 's/.* <mpm_gimp::simd::Baseline as [^>]*>::(scatter|particles|remap|stress|transport|stencils|gather|scatter_chunk|material)$/baseline \1/p;
        s/.* mpm_gimp::(world::passes|phases::kernels)::(avx2|avx512)::(scatter|particles|remap|stress|transport|stencils|gather|scatter_chunk|material)$/\2 \3/p' |
    sort | uniq -c | awk '{ n[$2] = n[$2] sprintf("  %s %d", $3, $1); t[$2] += $1 }
        END { for (i in n) printf "%-9s%s  (%d in all)\n", i, n[i], t[i] }' | sort
