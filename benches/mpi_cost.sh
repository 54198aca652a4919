#!/usr/bin/env bash
# What a split over MPI ranks costs against threads, on one scene in one run
# (benches/PERFORMANCE.md, "Past one machine"): mpm-gimp-mpi's split_check times the scene as
# one world on 1 and 2 threads (`--threads`), then split over 1 and 2 ranks (`--cost`: the
# step and the exchange after it, with the halo's bytes and messages), ROUNDS times
# interleaved, for the 2D and the 3D sand scenes SCALE times as long along the split axis.
# --bind-to none: Open MPI binds a lone rank to one core, where two threads would share it.
# Usage: bash benches/mpi_cost.sh [ROUNDS (3)] [SCALE (8)] [SUBSTEPS (50)]
set -euo pipefail
cd "$(dirname "$0")/.."
rounds=${1:-3}
scale=${2:-8}
substeps=${3:-50}
cargo build --release -p mpm-gimp-mpi --examples
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
check=target/release/examples/split_check
for case in 2d-sand-quadratic-flip-usl 3d-sand-quadratic-apic-musl; do
    for _ in $(seq "$rounds"); do
        for threads in 1 2; do
            mpirun --oversubscribe --bind-to none -np 1 "$check" --case "$case" --scale "$scale" \
                --substeps "$substeps" --threads "$threads"
        done
        for ranks in 1 2; do
            mpirun --oversubscribe --bind-to none -np "$ranks" "$check" --case "$case" --scale "$scale" \
                --substeps "$substeps" --cost
        done
    done
done
