/*
 * A C99 host of libmpm_gimp: an elastic block dropped on a sticky floor in a 1 m x 1 m box,
 * stepped for one second in a fixed 60 Hz frame loop. The world lives in a static array this
 * program owns; the library never allocates.
 *
 * Build against the single-precision static library (from the repository root):
 *   cargo build --release -p mpm-gimp-ffi
 *   gcc -std=c99 -Wall -Wextra -Werror -pedantic -I ffi/include ffi/examples/host.c \
 *       target/release/libmpm_gimp.a -lpthread -ldl -lm -o host
 * For the double-precision library (cargo build --release -p mpm-gimp-ffi --features f64)
 * add -DMPM_GIMP_F64.
 *
 * Output, one line at t = 0 and every 10 frames (the last one at t = 1 s):
 *   t=<s> com_y=<m> kinetic=<J> strain=<J> potential=<J> total=<J>
 * then one line
 *   done frames=<n> substeps=<n> particles=<n> frozen=<n> escaped=<n> lowest_y=<m>
 * Energies are per metre of thickness (the 2D world is plane strain). On failure the failing
 * call and mpm_status_string() go to stderr and the exit status is 1.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mpm_gimp.h"

/* The scene: 32 x 32 cells of 1/32 m, a 0.25 m square block (16 x 16 particles at the default
 * 2 particles per cell per axis) whose bottom starts 0.25 m above the grid's lower face. */
#define CELLS 32
#define BLOCK_PARTICLES (16 * 16)
/* Room for twice the block: a host sizes the world for what it may add later. */
#define PARTICLE_CAPACITY (2 * BLOCK_PARTICLES)
#define FRAMES 60
#define REPORT_EVERY 10

/* The world's memory. Its size is a bound for this scene in either precision; the program
 * checks it against mpm_memory_requirements() at run time. C99 has neither _Alignas nor
 * aligned_alloc, so the array has room to round its start up to the required alignment. */
#define ARENA_BYTES ((size_t)256 * 1024)
#define ARENA_ALIGN_ROOM 256
static unsigned char arena[ARENA_BYTES + ARENA_ALIGN_ROOM];

/* Positions copied out at the end: x, y per particle. */
static mpm_real positions[2 * PARTICLE_CAPACITY];

/* Exits with status 1 and the library's description when a call did not succeed. */
static void check(MpmStatus status, const char *call)
{
    if (status != MPM_STATUS_OK) {
        fprintf(stderr, "host: %s failed: %s\n", call, mpm_status_string(status));
        exit(EXIT_FAILURE);
    }
}

static MpmVec3 vec2(double x, double y)
{
    MpmVec3 v;
    v.x = (mpm_real)x;
    v.y = (mpm_real)y;
    v.z = (mpm_real)0;
    return v;
}

/* Prints one report line from the world's diagnostics. */
static void report(const MpmWorld *world)
{
    MpmDiagnostics d;
    check(mpm_world_diagnostics(world, &d), "mpm_world_diagnostics");
    printf("t=%.6f com_y=%.6f kinetic=%.6f strain=%.6f potential=%.6f total=%.6f\n", d.time,
           d.center_of_mass[1], d.kinetic, d.strain, d.potential,
           d.kinetic + d.strain + d.potential);
}

int main(void)
{
    /* valgrind 3.19 cannot decode AVX2: MPM_GIMP_SIMD=baseline selects the SSE2 passes,
     * which give bit-identical results. */
    const char *simd = getenv("MPM_GIMP_SIMD");
    if (simd != NULL && strcmp(simd, "baseline") == 0) mpm_simd_use_baseline_only();

    if (mpm_abi_version() != MPM_GIMP_ABI_VERSION) {
        fprintf(stderr, "host: library ABI version %lu, header %lu\n",
                (unsigned long)mpm_abi_version(), (unsigned long)MPM_GIMP_ABI_VERSION);
        return EXIT_FAILURE;
    }

    MpmWorldDef def = mpm_world_def_default();
    def.cell_size = (mpm_real)1 / CELLS;
    def.cells[0] = CELLS;
    def.cells[1] = CELLS;
    def.particle_capacity = PARTICLE_CAPACITY;
    def.material_capacity = 1;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;

    MpmMemoryRequirements req;
    check(mpm_memory_requirements(&def, &req), "mpm_memory_requirements");
    size_t misalign = (size_t)((uintptr_t)arena % req.align);
    size_t offset = misalign == 0 ? 0 : req.align - misalign;
    if (offset > sizeof arena || req.bytes > sizeof arena - offset) {
        fprintf(stderr,
                "host: the world needs %zu bytes aligned to %zu, the static array has %zu "
                "bytes (%zu after alignment): raise ARENA_BYTES\n",
                req.bytes, req.align, sizeof arena,
                offset > sizeof arena ? (size_t)0 : sizeof arena - offset);
        return EXIT_FAILURE;
    }
    MpmWorld *world = NULL;
    check(mpm_world_init(&def, arena + offset, sizeof arena - offset, &world), "mpm_world_init");

    /* A soft rubber (E = 0.1 MPa, the default density and Poisson's ratio): slower waves, so
     * longer stable substeps. */
    MpmMaterialDef material = mpm_material_def_default();
    material.youngs_modulus = (mpm_real)1e5;
    uint32_t material_id = 0;
    check(mpm_world_add_material(world, &material, &material_id), "mpm_world_add_material");

    MpmIdRange ids;
    check(mpm_world_fill_box(world, vec2(0.375, 0.25), vec2(0.625, 0.5), material_id,
                             vec2(0, 0), &ids),
          "mpm_world_fill_box");

    /* The kernel splits each frame into equal substeps no longer than the stable one. */
    const mpm_real frame_dt = (mpm_real)(1.0 / FRAMES);
    unsigned long substeps = 0, frozen = 0, escaped = 0;
    report(world);
    for (int frame = 1; frame <= FRAMES; ++frame) {
        MpmStepReport step;
        check(mpm_world_step(world, frame_dt, &step), "mpm_world_step");
        substeps += step.substeps;
        frozen += step.frozen;
        escaped += step.escaped;
        if (frame % REPORT_EVERY == 0 || frame == FRAMES) report(world);
    }

    size_t written = 0;
    check(mpm_world_copy_positions(world, positions, sizeof positions / sizeof positions[0],
                                   &written),
          "mpm_world_copy_positions");
    if (written < 2) {
        fprintf(stderr, "host: no particle positions to read\n");
        return EXIT_FAILURE;
    }
    mpm_real lowest_y = positions[1];
    for (size_t i = 3; i < written; i += 2) {
        if (positions[i] < lowest_y) lowest_y = positions[i];
    }

    printf("done frames=%d substeps=%lu particles=%lu frozen=%lu escaped=%lu lowest_y=%.6f\n",
           FRAMES, substeps, (unsigned long)(written / 2), frozen, escaped, (double)lowest_y);
    return EXIT_SUCCESS;
}
