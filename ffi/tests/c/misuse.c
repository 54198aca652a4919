/*
 * Misuse of the C interface from C. Every refused call must
 *   - return the status the header documents for its misuse,
 *   - leave every world unchanged: the FNV-1a 64 hash of each world's memory over its
 *     mpm_world_bytes extent (which covers the header and every column) is compared before and
 *     after,
 *   - write no output: every output pointer points into a sentinel area that is checked after
 *     the call (and the memory handed to a refused mpm_world_init or mpm_world_open is checked
 *     too).
 * Accepted calls between the checks show that the hash does see a change.
 *
 * The library is Rust and not instrumented by AddressSanitizer, so a read past a short array
 * inside it would go unseen by ASan: the check that an over-capacity count reads no array also
 * passes arrays that lie in a page mapped without access (where mmap exists), so that any read
 * crashes the program.
 *
 * One line per check ("ok <name>: <status string>"); the first failure prints
 * "FAIL <name>: <why>" and exits with status 1. The last line on success is
 * "all <n> misuse checks passed". tests/c_checks.rs builds this file with strict warnings and
 * with AddressSanitizer and UndefinedBehaviorSanitizer, and runs it.
 */
#if defined(__unix__) || defined(__APPLE__)
/* mmap for the no-access page (not in strict C99). */
#define _DEFAULT_SOURCE
#define MISUSE_HAVE_MMAN 1
#endif

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef MISUSE_HAVE_MMAN
#include <sys/mman.h>
#include <unistd.h>
#ifndef MAP_ANONYMOUS
#define MAP_ANONYMOUS MAP_ANON
#endif
#endif

#include "mpm_gimp.h"

#include "check.h"

/* ---- memory --------------------------------------------------------------------------- */

/* `bytes` at `align` (a power of two) inside a block from malloc, plus `slack` bytes after. */
typedef struct {
    unsigned char *raw;
    unsigned char *at;
} Block;

static Block block_new(size_t bytes, size_t align, size_t slack) {
    Block b;
    size_t offset;
    b.raw = (unsigned char *)malloc(bytes + align + slack);
    if (b.raw == NULL) {
        fail("malloc", "out of memory");
    }
    offset = (align - (size_t)((uintptr_t)b.raw % align)) % align;
    b.at = b.raw + offset;
    return b;
}

/* ---- scenes --------------------------------------------------------------------------- */

/* 2D: 20 x 20 cells of 0.05 m (GIMP: particles admitted in [0.05, 0.95]), 64 particles, 2
 * materials. */
static MpmWorldDef def_2d(void) { return grid_2d(64, 2); }

/* 3D: 8 x 8 x 8 cells of 0.05 m (admitted in [0.05, 0.35] per axis), 32 particles. */
static MpmWorldDef def_3d(void) {
    MpmWorldDef d = mpm_world_def_default();
    d.dimension = MPM_DIMENSION_SPACE3D;
    d.cells[0] = 8;
    d.cells[1] = 8;
    d.cells[2] = 8;
    d.cell_size = R(0.05);
    d.particle_capacity = 32;
    d.material_capacity = 1;
    return d;
}

/* The 2D definition with every effect declared: APIC, damping (a constant grid schedule, a
 * thermostat, per-particle columns), particle forces, 8 tractions, a body force, and heat
 * conduction and diffusion, both with sources. */
static MpmWorldDef def_2d_effects(void) {
    MpmWorldDef d = def_2d();
    d.material_capacity = 1;
    declare_every_effect(&d);
    return d;
}

/* The 3D definition with damping (grid only: no per-particle columns), particle forces, 4
 * tractions and heat conduction without sources (every face insulated); FLIP. */
static MpmWorldDef def_3d_effects(void) {
    MpmWorldDef d = def_3d();
    d.effects.damping.declared = 1;
    d.effects.damping.grid.points = 1;
    d.effects.damping.grid.values[0] = R(0.5);
    d.effects.particle_forces = 1;
    d.effects.traction_capacity = 4;
    d.effects.heat.declared = 1;
    return d;
}

/* Axisymmetric: the 2D grid, GIMP, with the grid's lower x face one cell (GIMP's margin)
 * below the axis, origin.x = -0.05, so that the wall plane is r = 0 and particles are admitted
 * at r in [0, 0.9]; heat conduction and diffusion declared (so that a material expands and
 * swells), 2 materials. */
static MpmWorldDef def_axisym(void) {
    MpmWorldDef d = def_2d();
    d.dimension = MPM_DIMENSION_AXISYMMETRIC2D;
    d.origin = v3(-0.05, 0.0, 0.0);
    d.effects.heat.declared = 1;
    d.effects.diffusion.declared = 1;
    return d;
}

/* Structure-of-arrays storage for a few particles. */
#define BATCH_MAX 64
typedef struct {
    mpm_real x[3][BATCH_MAX];
    mpm_real v[3][BATCH_MAX];
    mpm_real mass[BATCH_MAX];
    mpm_real volume[BATCH_MAX];
    uint32_t material[BATCH_MAX];
} Batch;

/* `n` valid particles of material 0 on a row starting at (x0, y0, z0), spacing 0.01 m. */
static void batch_fill(Batch *b, size_t n, double x0, double y0, double z0) {
    size_t i;
    for (i = 0; i < n; i++) {
        b->x[0][i] = R(x0 + 0.01 * (double)(i % 8));
        b->x[1][i] = R(y0 + 0.01 * (double)(i / 8));
        b->x[2][i] = R(z0);
        b->v[0][i] = R(0.5);
        b->v[1][i] = R(-0.25);
        b->v[2][i] = R(0.125);
        b->mass[i] = R(0.001);
        b->volume[i] = R(0.000001);
        b->material[i] = 0;
    }
}

static MpmParticleArrays arrays_of(const Batch *b) {
    MpmParticleArrays a;
    int k;
    for (k = 0; k < 3; k++) {
        a.position[k] = b->x[k];
        a.velocity[k] = b->v[k];
    }
    a.mass = b->mass;
    a.volume = b->volume;
    a.material = b->material;
    return a;
}

/* ---- the checks ----------------------------------------------------------------------- */

static MpmWorld *g_w2;      /* the 2D world */
static MpmWorld *g_w3;      /* the 3D world */
static MpmWorld *g_we2;     /* the 2D world with every effect declared */
static MpmWorld *g_we3;     /* the 3D world with damping, forces, tractions and heat */
static MpmWorld *g_wa;      /* the axisymmetric world */
static size_t g_w2_bytes;   /* its extent */
static MpmWorldDef g_def2;  /* its definition */

/* Every pointer argument of every function NULL in turn: MPM_STATUS_NULL_POINTER. */
static void null_pointers(void) {
    MpmWorldDef d = g_def2;
    MpmMaterialDef m = mpm_material_def_default();
    MpmMemoryRequirements req;
    Batch b;
    MpmParticleArrays a, a_null;
    MpmVec3 lo = v3(0.2, 0.2, 0.0), hi = v3(0.25, 0.25, 0.0), zero = v3(0, 0, 0);
    const mpm_real dt = R(0.001);
    Block init_mem;
    size_t len = 2 * BATCH_MAX;
    int k;

    if (mpm_memory_requirements(&d, &req) != MPM_STATUS_OK) {
        fail("null: setup", "mpm_memory_requirements refused the 2D definition");
    }
    init_mem = block_new(req.bytes, req.align, 0);
    memset(init_mem.at, PATTERN, req.bytes);

    REFUSED("null: mpm_memory_requirements def", MPM_STATUS_NULL_POINTER,
            mpm_memory_requirements(NULL, OUT(MpmMemoryRequirements)));
    REFUSED("null: mpm_memory_requirements requirements_out", MPM_STATUS_NULL_POINTER,
            mpm_memory_requirements(&d, NULL));

    REFUSED("null: mpm_world_init def", MPM_STATUS_NULL_POINTER,
            mpm_world_init(NULL, init_mem.at, req.bytes, OUT(MpmWorld *)));
    REFUSED("null: mpm_world_init memory", MPM_STATUS_NULL_POINTER,
            mpm_world_init(&d, NULL, req.bytes, OUT(MpmWorld *)));
    REFUSED("null: mpm_world_init world_out", MPM_STATUS_NULL_POINTER,
            mpm_world_init(&d, init_mem.at, req.bytes, NULL));
    expect_true("null: mpm_world_init left the memory untouched",
                pattern_intact(init_mem.at, req.bytes));
    free(init_mem.raw);

    REFUSED("null: mpm_world_open memory", MPM_STATUS_NULL_POINTER,
            mpm_world_open(NULL, g_w2_bytes, OUT(MpmWorld *)));
    REFUSED("null: mpm_world_open world_out", MPM_STATUS_NULL_POINTER,
            mpm_world_open(g_w2, g_w2_bytes, NULL));

    REFUSED("null: mpm_world_bytes world", MPM_STATUS_NULL_POINTER,
            mpm_world_bytes(NULL, OUT(size_t)));
    REFUSED("null: mpm_world_bytes bytes_out", MPM_STATUS_NULL_POINTER,
            mpm_world_bytes(g_w2, NULL));

    REFUSED("null: mpm_world_get_def world", MPM_STATUS_NULL_POINTER,
            mpm_world_get_def(NULL, OUT(MpmWorldDef)));
    REFUSED("null: mpm_world_get_def def_out", MPM_STATUS_NULL_POINTER,
            mpm_world_get_def(g_w2, NULL));

    REFUSED("null: mpm_world_add_material world", MPM_STATUS_NULL_POINTER,
            mpm_world_add_material(NULL, &m, OUT(uint32_t)));
    REFUSED("null: mpm_world_add_material def", MPM_STATUS_NULL_POINTER,
            mpm_world_add_material(g_w2, NULL, OUT(uint32_t)));
    REFUSED("null: mpm_world_add_material id_out", MPM_STATUS_NULL_POINTER,
            mpm_world_add_material(g_w2, &m, NULL));

    batch_fill(&b, 2, 0.2, 0.2, 0.0);
    a = arrays_of(&b);
    REFUSED("null: mpm_world_add_particles world", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles(NULL, &a, 2, OUT(MpmIdRange)));
    REFUSED("null: mpm_world_add_particles arrays", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles(g_w2, NULL, 2, OUT(MpmIdRange)));
    REFUSED("null: mpm_world_add_particles ids_out", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles(g_w2, &a, 2, NULL));
    for (k = 0; k < 2; k++) {
        char name[96];
        a_null = a;
        a_null.position[k] = NULL;
        snprintf(name, sizeof name, "null: mpm_world_add_particles arrays.position[%d] (2D)", k);
        REFUSED(name, MPM_STATUS_NULL_POINTER,
                mpm_world_add_particles(g_w2, &a_null, 2, OUT(MpmIdRange)));
        a_null = a;
        a_null.velocity[k] = NULL;
        snprintf(name, sizeof name, "null: mpm_world_add_particles arrays.velocity[%d] (2D)", k);
        REFUSED(name, MPM_STATUS_NULL_POINTER,
                mpm_world_add_particles(g_w2, &a_null, 2, OUT(MpmIdRange)));
    }
    a_null = a;
    a_null.mass = NULL;
    REFUSED("null: mpm_world_add_particles arrays.mass", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles(g_w2, &a_null, 2, OUT(MpmIdRange)));
    a_null = a;
    a_null.volume = NULL;
    REFUSED("null: mpm_world_add_particles arrays.volume", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles(g_w2, &a_null, 2, OUT(MpmIdRange)));
    a_null = a;
    a_null.material = NULL;
    REFUSED("null: mpm_world_add_particles arrays.material", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles(g_w2, &a_null, 2, OUT(MpmIdRange)));
    a_null = a;
    a_null.material = NULL;
    REFUSED("null: mpm_world_add_particles arrays.material with count 0",
            MPM_STATUS_NULL_POINTER, mpm_world_add_particles(g_w2, &a_null, 0, OUT(MpmIdRange)));

    batch_fill(&b, 2, 0.2, 0.2, 0.2);
    a = arrays_of(&b);
    for (k = 0; k < 3; k++) {
        char name[96];
        a_null = a;
        a_null.position[k] = NULL;
        snprintf(name, sizeof name, "null: mpm_world_add_particles arrays.position[%d] (3D)", k);
        REFUSED(name, MPM_STATUS_NULL_POINTER,
                mpm_world_add_particles(g_w3, &a_null, 2, OUT(MpmIdRange)));
        a_null = a;
        a_null.velocity[k] = NULL;
        snprintf(name, sizeof name, "null: mpm_world_add_particles arrays.velocity[%d] (3D)", k);
        REFUSED(name, MPM_STATUS_NULL_POINTER,
                mpm_world_add_particles(g_w3, &a_null, 2, OUT(MpmIdRange)));
    }

    REFUSED("null: mpm_world_fill_box world", MPM_STATUS_NULL_POINTER,
            mpm_world_fill_box(NULL, lo, hi, 0, zero, OUT(MpmIdRange)));
    REFUSED("null: mpm_world_fill_box ids_out", MPM_STATUS_NULL_POINTER,
            mpm_world_fill_box(g_w2, lo, hi, 0, zero, NULL));
    REFUSED("null: mpm_world_fill_disk world", MPM_STATUS_NULL_POINTER,
            mpm_world_fill_disk(NULL, lo, R(0.02), 0, zero, OUT(MpmIdRange)));
    REFUSED("null: mpm_world_fill_disk ids_out", MPM_STATUS_NULL_POINTER,
            mpm_world_fill_disk(g_w2, lo, R(0.02), 0, zero, NULL));
    REFUSED("null: mpm_world_fill_sphere world", MPM_STATUS_NULL_POINTER,
            mpm_world_fill_sphere(NULL, v3(0.2, 0.2, 0.2), R(0.02), 0, zero, OUT(MpmIdRange)));
    REFUSED("null: mpm_world_fill_sphere ids_out", MPM_STATUS_NULL_POINTER,
            mpm_world_fill_sphere(g_w3, v3(0.2, 0.2, 0.2), R(0.02), 0, zero, NULL));

    REFUSED("null: mpm_world_stable_dt world", MPM_STATUS_NULL_POINTER,
            mpm_world_stable_dt(NULL, OUT(mpm_real)));
    REFUSED("null: mpm_world_stable_dt dt_out", MPM_STATUS_NULL_POINTER,
            mpm_world_stable_dt(g_w2, NULL));

    REFUSED("null: mpm_world_step world", MPM_STATUS_NULL_POINTER,
            mpm_world_step(NULL, dt, OUT(MpmStepReport)));
    REFUSED("null: mpm_world_step report_out", MPM_STATUS_NULL_POINTER,
            mpm_world_step(g_w2, dt, NULL));

    REFUSED("null: mpm_world_particles world", MPM_STATUS_NULL_POINTER,
            mpm_world_particles(NULL, OUT(MpmParticlesView)));
    REFUSED("null: mpm_world_particles view_out", MPM_STATUS_NULL_POINTER,
            mpm_world_particles(g_w2, NULL));

    REFUSED("null: mpm_world_diagnostics world", MPM_STATUS_NULL_POINTER,
            mpm_world_diagnostics(NULL, OUT(MpmDiagnostics)));
    REFUSED("null: mpm_world_diagnostics diagnostics_out", MPM_STATUS_NULL_POINTER,
            mpm_world_diagnostics(g_w2, NULL));

#define NULL_COPY(fn, T) \
    REFUSED("null: " #fn " world", MPM_STATUS_NULL_POINTER, \
            fn(NULL, OUT(T), len, OUT_AT(size_t, WRITTEN_AT))); \
    REFUSED("null: " #fn " out", MPM_STATUS_NULL_POINTER, \
            fn(g_w2, NULL, len, OUT_AT(size_t, WRITTEN_AT))); \
    REFUSED("null: " #fn " out with out_len 0", MPM_STATUS_NULL_POINTER, \
            fn(g_w2, NULL, 0, OUT_AT(size_t, WRITTEN_AT))); \
    REFUSED("null: " #fn " written_out", MPM_STATUS_NULL_POINTER, fn(g_w2, OUT(T), len, NULL))

    NULL_COPY(mpm_world_copy_positions, mpm_real);
    NULL_COPY(mpm_world_copy_velocities, mpm_real);
    NULL_COPY(mpm_world_copy_stress, mpm_real);
    NULL_COPY(mpm_world_copy_jacobians, mpm_real);
    NULL_COPY(mpm_world_copy_status, uint32_t);
#undef NULL_COPY

    /* The effects' calls, on the worlds that declare the effects. */
    {
        const mpm_real f[2] = {R(0.5), R(0.25)};
        REFUSED("null: mpm_world_set_particle_forces world", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_forces(NULL, 0, f, f, f, 1));
        REFUSED("null: mpm_world_set_particle_forces fx (2D)", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_forces(g_we2, 0, NULL, f, NULL, 1));
        REFUSED("null: mpm_world_set_particle_forces fy (2D)", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_forces(g_we2, 0, f, NULL, f, 1));
        REFUSED("null: mpm_world_set_particle_forces fx with count 0", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_forces(g_we2, 0, NULL, f, NULL, 0));
        REFUSED("null: mpm_world_set_particle_forces fx (3D)", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_forces(g_we3, 0, NULL, f, f, 1));
        REFUSED("null: mpm_world_set_particle_forces fy (3D)", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_forces(g_we3, 0, f, NULL, f, 1));
        REFUSED("null: mpm_world_set_particle_forces fz (3D)", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_forces(g_we3, 0, f, f, NULL, 1));
        /* Pointers are checked before the declaration. */
        REFUSED("null: mpm_world_set_particle_forces fx on a world without forces",
                MPM_STATUS_NULL_POINTER, mpm_world_set_particle_forces(g_w2, 0, NULL, f, f, 1));

        REFUSED("null: mpm_world_set_particle_damping world", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_damping(NULL, 0, f, f, 1));
        REFUSED("null: mpm_world_set_particle_damping alpha_g", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_damping(g_we2, 0, NULL, f, 1));
        REFUSED("null: mpm_world_set_particle_damping alpha_p", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_damping(g_we2, 0, f, NULL, 1));
        REFUSED("null: mpm_world_set_particle_damping alpha_p with count 0",
                MPM_STATUS_NULL_POINTER, mpm_world_set_particle_damping(g_we2, 0, f, NULL, 0));

        REFUSED("null: mpm_world_add_tractions world", MPM_STATUS_NULL_POINTER,
                mpm_world_add_tractions(NULL, 0, 1, MPM_FACE_Y_MAX, zero, OUT(MpmIdRange)));
        REFUSED("null: mpm_world_add_tractions ids_out", MPM_STATUS_NULL_POINTER,
                mpm_world_add_tractions(g_we2, 0, 1, MPM_FACE_Y_MAX, zero, NULL));
        REFUSED("null: mpm_world_add_surface_tractions world", MPM_STATUS_NULL_POINTER,
                mpm_world_add_surface_tractions(NULL, 0, 1, v3(0, 1, 0), R(0.1), zero,
                                                OUT(MpmIdRange)));
        REFUSED("null: mpm_world_add_surface_tractions ids_out", MPM_STATUS_NULL_POINTER,
                mpm_world_add_surface_tractions(g_we2, 0, 1, v3(0, 1, 0), R(0.1), zero, NULL));
        REFUSED("null: mpm_world_add_follower_tractions world", MPM_STATUS_NULL_POINTER,
                mpm_world_add_follower_tractions(NULL, 0, 1, v3(0, 1, 0), R(0.1), zero,
                                                 OUT(MpmIdRange)));
        REFUSED("null: mpm_world_add_follower_tractions ids_out", MPM_STATUS_NULL_POINTER,
                mpm_world_add_follower_tractions(g_we2, 0, 1, v3(0, 1, 0), R(0.1), zero, NULL));
        REFUSED("null: mpm_world_set_traction_schedule world", MPM_STATUS_NULL_POINTER,
                mpm_world_set_traction_schedule(NULL, 0, 1, 1));
        REFUSED("null: mpm_world_clear_tractions world", MPM_STATUS_NULL_POINTER,
                mpm_world_clear_tractions(NULL));
        REFUSED("null: mpm_world_remove_tractions world", MPM_STATUS_NULL_POINTER,
                mpm_world_remove_tractions(NULL, 0, 0));
        REFUSED("null: mpm_world_traction_count world", MPM_STATUS_NULL_POINTER,
                mpm_world_traction_count(NULL, OUT(size_t)));
        REFUSED("null: mpm_world_remove_particles_in_collider world", MPM_STATUS_NULL_POINTER,
                mpm_world_remove_particles_in_collider(NULL, 0, OUT(uint32_t)));
        REFUSED("null: mpm_world_remove_particles_in_collider removed_out",
                MPM_STATUS_NULL_POINTER, mpm_world_remove_particles_in_collider(g_we2, 0, NULL));
        REFUSED("null: mpm_world_traction_count count_out", MPM_STATUS_NULL_POINTER,
                mpm_world_traction_count(g_we2, NULL));
        REFUSED("null: mpm_world_feedback_alpha world", MPM_STATUS_NULL_POINTER,
                mpm_world_feedback_alpha(NULL, OUT(double)));
        REFUSED("null: mpm_world_feedback_alpha alpha_out", MPM_STATUS_NULL_POINTER,
                mpm_world_feedback_alpha(g_we2, NULL));

        REFUSED("null: mpm_world_set_particle_scalar world", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_scalar(NULL, MPM_SCALAR_FIELD_TEMPERATURE, 0, f, 1));
        REFUSED("null: mpm_world_set_particle_scalar values", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_scalar(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, 0, NULL, 1));
        REFUSED("null: mpm_world_set_particle_scalar values (concentration)",
                MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_scalar(g_we2, MPM_SCALAR_FIELD_CONCENTRATION, 0, NULL, 1));
        REFUSED("null: mpm_world_set_particle_scalar values with count 0",
                MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_scalar(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, 0, NULL, 0));
        REFUSED("null: mpm_world_set_particle_sources world", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_sources(NULL, MPM_SCALAR_FIELD_TEMPERATURE, 0, f, 1));
        REFUSED("null: mpm_world_set_particle_sources values", MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_sources(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, 0, NULL, 1));
        REFUSED("null: mpm_world_set_particle_sources values (concentration)",
                MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_sources(g_we2, MPM_SCALAR_FIELD_CONCENTRATION, 0, NULL, 1));
        REFUSED("null: mpm_world_set_particle_sources values with count 0",
                MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_sources(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, 0, NULL, 0));
        /* Pointers are checked before the field's number and the declaration. */
        REFUSED("null: mpm_world_set_particle_scalar values with a field out of range",
                MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_scalar(g_we2, (MpmScalarField)7u, 0, NULL, 1));
        REFUSED("null: mpm_world_set_particle_scalar values on a world without heat",
                MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_scalar(g_w2, MPM_SCALAR_FIELD_TEMPERATURE, 0, NULL, 1));
        REFUSED("null: mpm_world_set_particle_sources values on a world without sources",
                MPM_STATUS_NULL_POINTER,
                mpm_world_set_particle_sources(g_we3, MPM_SCALAR_FIELD_TEMPERATURE, 0, NULL, 1));
    }
}

/* World pointers that are not a world: misaligned, or aligned memory without a world. */
static void not_a_world(void) {
    Block zero = block_new(g_w2_bytes, 64, 0);
    MpmWorld *bad[2];
    MpmStatus want[2] = {MPM_STATUS_BUFFER_MISALIGNED, MPM_STATUS_NOT_A_WORLD};
    const char *what[2] = {"misaligned world pointer", "zeroed memory as a world"};
    MpmMaterialDef m = mpm_material_def_default();
    Batch b;
    MpmParticleArrays a;
    int i;

    memset(zero.at, 0, g_w2_bytes);
    /* One byte into the 2D world: never read, the alignment is checked first. */
    bad[0] = (MpmWorld *)(void *)((unsigned char *)(void *)g_w2 + 1);
    bad[1] = (MpmWorld *)(void *)zero.at;
    batch_fill(&b, 1, 0.2, 0.2, 0.0);
    a = arrays_of(&b);

    for (i = 0; i < 2; i++) {
        char name[128];
        MpmWorld *w = bad[i];
#define BAD_WORLD(fn, call) \
    snprintf(name, sizeof name, "%s: %s", what[i], fn); \
    REFUSED(name, want[i], call)
        BAD_WORLD("mpm_world_bytes", mpm_world_bytes(w, OUT(size_t)));
        BAD_WORLD("mpm_world_get_def", mpm_world_get_def(w, OUT(MpmWorldDef)));
        BAD_WORLD("mpm_world_add_material", mpm_world_add_material(w, &m, OUT(uint32_t)));
        BAD_WORLD("mpm_world_add_particles",
                  mpm_world_add_particles(w, &a, 1, OUT(MpmIdRange)));
        BAD_WORLD("mpm_world_fill_box", mpm_world_fill_box(w, v3(0.2, 0.2, 0), v3(0.3, 0.3, 0),
                                                           0, v3(0, 0, 0), OUT(MpmIdRange)));
        BAD_WORLD("mpm_world_fill_disk",
                  mpm_world_fill_disk(w, v3(0.2, 0.2, 0), R(0.02), 0, v3(0, 0, 0),
                                      OUT(MpmIdRange)));
        BAD_WORLD("mpm_world_fill_sphere",
                  mpm_world_fill_sphere(w, v3(0.2, 0.2, 0.2), R(0.02), 0, v3(0, 0, 0),
                                        OUT(MpmIdRange)));
        BAD_WORLD("mpm_world_stable_dt", mpm_world_stable_dt(w, OUT(mpm_real)));
        BAD_WORLD("mpm_world_step", mpm_world_step(w, R(0.001), OUT(MpmStepReport)));
        BAD_WORLD("mpm_world_particles", mpm_world_particles(w, OUT(MpmParticlesView)));
        BAD_WORLD("mpm_world_copy_positions",
                  mpm_world_copy_positions(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        BAD_WORLD("mpm_world_copy_velocities",
                  mpm_world_copy_velocities(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        BAD_WORLD("mpm_world_copy_stress",
                  mpm_world_copy_stress(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        BAD_WORLD("mpm_world_copy_jacobians",
                  mpm_world_copy_jacobians(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        BAD_WORLD("mpm_world_copy_status",
                  mpm_world_copy_status(w, OUT(uint32_t), 16, OUT_AT(size_t, WRITTEN_AT)));
        BAD_WORLD("mpm_world_diagnostics", mpm_world_diagnostics(w, OUT(MpmDiagnostics)));
        BAD_WORLD("mpm_world_set_particle_forces",
                  mpm_world_set_particle_forces(w, 0, b.v[0], b.v[1], b.v[2], 1));
        BAD_WORLD("mpm_world_set_particle_damping",
                  mpm_world_set_particle_damping(w, 0, b.mass, b.volume, 1));
        BAD_WORLD("mpm_world_add_tractions",
                  mpm_world_add_tractions(w, 0, 1, MPM_FACE_Y_MAX, v3(0, -1, 0), OUT(MpmIdRange)));
        BAD_WORLD("mpm_world_add_surface_tractions",
                  mpm_world_add_surface_tractions(w, 0, 1, v3(0, 1, 0), R(0.1), v3(0, -1, 0),
                                                  OUT(MpmIdRange)));
        BAD_WORLD("mpm_world_add_follower_tractions",
                  mpm_world_add_follower_tractions(w, 0, 1, v3(0, 1, 0), R(0.1), v3(-1, 0, 0),
                                                   OUT(MpmIdRange)));
        BAD_WORLD("mpm_world_set_traction_schedule", mpm_world_set_traction_schedule(w, 0, 1, 1));
        BAD_WORLD("mpm_world_clear_tractions", mpm_world_clear_tractions(w));
        BAD_WORLD("mpm_world_remove_tractions", mpm_world_remove_tractions(w, 0, 1));
        BAD_WORLD("mpm_world_traction_count", mpm_world_traction_count(w, OUT(size_t)));
        BAD_WORLD("mpm_world_remove_particles_in_collider",
                  mpm_world_remove_particles_in_collider(w, 0, OUT(uint32_t)));
        BAD_WORLD("mpm_world_feedback_alpha", mpm_world_feedback_alpha(w, OUT(double)));
        BAD_WORLD("mpm_world_set_particle_scalar",
                  mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, b.mass, 1));
        BAD_WORLD("mpm_world_set_particle_sources",
                  mpm_world_set_particle_sources(w, MPM_SCALAR_FIELD_CONCENTRATION, 0, b.mass, 1));
#undef BAD_WORLD
    }
    {
        size_t k, nonzero = 0;
        for (k = 0; k < g_w2_bytes; k++) {
            nonzero += zero.at[k] != 0;
        }
        expect_true("not a world: the zeroed memory stayed zero", nonzero == 0);
    }
    free(zero.raw);
}

/* mpm_world_init on bad memory, bad definitions and out-of-range enums: refused, and the
 * memory (filled with a pattern) untouched. mpm_memory_requirements refuses the same
 * definitions. */
static Block g_init_mem;
static MpmMemoryRequirements g_init_req;

static void init_refused(const char *name, MpmStatus want, const MpmWorldDef *d) {
    char full[160];
    snprintf(full, sizeof full, "%s: mpm_memory_requirements", name);
    REFUSED(full, want, mpm_memory_requirements(d, OUT(MpmMemoryRequirements)));
    memset(g_init_mem.raw, PATTERN, g_init_req.bytes + 2 * g_init_req.align);
    snprintf(full, sizeof full, "%s: mpm_world_init", name);
    REFUSED(full, want, mpm_world_init(d, g_init_mem.at, g_init_req.bytes, OUT(MpmWorld *)));
    if (!pattern_intact(g_init_mem.raw, g_init_req.bytes + 2 * g_init_req.align)) {
        fail(full, "the refused init wrote to the memory");
    }
}

/* The transfer and the effects of a definition: enums and flags out of range, effect values
 * out of range or not finite. Fields of an effect that is not declared are not read. */
static void effects_def_misuse(void) {
    static const uint32_t bad_flag[] = {2u, 0x80000000u, 0xFFFFFFFFu};
    static const uint32_t bad_kind[] = {3u, 0x80000000u, 0xFFFFFFFFu};
    /* 5 and 6 with an order above the low byte are XPIC and FMPM; 7 is no transfer. */
    static const uint32_t bad_transfer[] = {7u, 0x80000000u, 0xFFFFFFFFu};
    /* XPIC and FMPM of an order out of range: 0, XPIC(9), FMPM(3). */
    static const uint32_t bad_order[] = {MPM_TRANSFER_XPIC, MPM_TRANSFER_XPIC + 256u * 9u,
                                         MPM_TRANSFER_FMPM + 256u * 3u};
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    const char *label[3] = {"NaN", "+inf", "-inf"};
    MpmWorldDef d, damped = g_def2, fed, zoned, heated = g_def2, diffused = g_def2;
    MpmMemoryRequirements req;
    unsigned k;
    int j, f;

    heated.effects.heat.declared = 1;
    diffused.effects.diffusion.declared = 1;
    damped.effects.damping.declared = 1;
    fed = damped;
    fed.effects.damping.feedback.declared = 1;
    fed.effects.damping.feedback.gain = R(1.0);
    fed.effects.damping.feedback.max_alpha = R(1.0);
    zoned = damped;
    zoned.effects.damping.zone_count = 1;
    zoned.effects.damping.zones[0].max = v3(0.5, 0.5, 0.0);
    zoned.effects.damping.zones[0].rate = R(2.0);
    {
        MpmWorldDef ramped = zoned;
        ramped.effects.damping.zones[0].ramped = 1;
        ramped.effects.damping.zones[0].ramp_face = MPM_FACE_Y_MAX;
        ACCEPTED("init: a zone graded toward Y_MAX (2D)", 0,
                 mpm_memory_requirements(&ramped, &req));
    }

    d = g_def2;
    d.transfer = MPM_TRANSFER_FMPM + 256u * 2u;
    d.update_order = MPM_UPDATE_ORDER_USL;
    init_refused("init: FMPM(2) with USL", MPM_STATUS_INVALID_TRANSFER, &d);
    for (k = 0; k < sizeof bad_flag / sizeof bad_flag[0]; k++) {
        char name[96];
        const uint32_t v = bad_flag[k];
        d = g_def2;
        d.transfer = bad_transfer[k]; /* 2, 3 and 4 are FLIP_PARTICLE_VELOCITY, MLS, FLIP_MOMENTUM */
        snprintf(name, sizeof name, "init: transfer %u", (unsigned)bad_transfer[k]);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = g_def2;
        d.transfer = bad_order[k];
        snprintf(name, sizeof name, "init: transfer order %u", (unsigned)bad_order[k]);
        init_refused(name, MPM_STATUS_INVALID_TRANSFER, &d);
        d = g_def2;
        d.effects.damping.declared = v;
        snprintf(name, sizeof name, "init: damping.declared %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = damped;
        d.effects.damping.per_particle = v;
        snprintf(name, sizeof name, "init: damping.per_particle %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = damped;
        d.effects.damping.feedback.declared = v;
        snprintf(name, sizeof name, "init: damping.feedback.declared %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = damped;
        d.effects.damping.grid_on_force = v;
        snprintf(name, sizeof name, "init: damping.grid_on_force %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = zoned;
        d.effects.damping.zones[0].ramped = v;
        snprintf(name, sizeof name, "init: damping.zones[0].ramped %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = zoned;
        d.effects.damping.zones[0].ramped = 1;
        d.effects.damping.zones[0].ramp_face = v == 2u ? 6u : v;
        snprintf(name, sizeof name, "init: damping.zones[0].ramp_face %u",
                 (unsigned)d.effects.damping.zones[0].ramp_face);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = g_def2;
        d.effects.particle_forces = v;
        snprintf(name, sizeof name, "init: particle_forces %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = g_def2;
        d.effects.heat.declared = v;
        snprintf(name, sizeof name, "init: heat.declared %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = heated;
        d.effects.heat.sources = v;
        snprintf(name, sizeof name, "init: heat.sources %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = g_def2;
        d.effects.diffusion.declared = v;
        snprintf(name, sizeof name, "init: diffusion.declared %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = diffused;
        d.effects.diffusion.sources = v;
        snprintf(name, sizeof name, "init: diffusion.sources %u", (unsigned)v);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
    }

    /* Face kinds of a declared transport out of the enum, on every face. */
    for (k = 0; k < sizeof bad_kind / sizeof bad_kind[0]; k++) {
        for (f = 0; f < 6; f++) {
            char name[96];
            d = heated;
            d.effects.heat.faces[f].kind = bad_kind[k];
            snprintf(name, sizeof name, "init: heat.faces[%d].kind %u", f, (unsigned)bad_kind[k]);
            init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
            d = diffused;
            d.effects.diffusion.faces[f].kind = bad_kind[k];
            snprintf(name, sizeof name, "init: diffusion.faces[%d].kind %u", f,
                     (unsigned)bad_kind[k]);
            init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        }
    }

#define BAD_EFFECT(name, base, stmt) \
    d = (base); \
    stmt; \
    init_refused((name), MPM_STATUS_INVALID_EFFECT, &d)
    BAD_EFFECT("init: damping.grid.points 9", damped, d.effects.damping.grid.points = 9);
    BAD_EFFECT("init: damping.grid.points 0xFFFFFFFF", damped,
               d.effects.damping.grid.points = 0xFFFFFFFFu);
    BAD_EFFECT("init: damping.grid times equal", damped,
               (d.effects.damping.grid.points = 2, d.effects.damping.grid.times[0] = R(0.5),
                d.effects.damping.grid.times[1] = R(0.5)));
    BAD_EFFECT("init: damping.grid times decreasing", damped,
               (d.effects.damping.grid.points = 2, d.effects.damping.grid.times[0] = R(0.5),
                d.effects.damping.grid.times[1] = R(0.25)));
    BAD_EFFECT("init: damping.grid value -1", damped,
               (d.effects.damping.grid.points = 1, d.effects.damping.grid.values[0] = R(-1.0)));
    BAD_EFFECT("init: damping.particle value -0.5", damped,
               (d.effects.damping.particle.points = 2,
                d.effects.damping.particle.times[1] = R(1.0),
                d.effects.damping.particle.values[1] = R(-0.5)));
    BAD_EFFECT("init: damping.particle.points 9", damped, d.effects.damping.particle.points = 9);
    BAD_EFFECT("init: feedback gain 0", fed, d.effects.damping.feedback.gain = R(0.0));
    BAD_EFFECT("init: feedback gain -1", fed, d.effects.damping.feedback.gain = R(-1.0));
    BAD_EFFECT("init: feedback max_alpha 0", fed, d.effects.damping.feedback.max_alpha = R(0.0));
    BAD_EFFECT("init: feedback max_alpha -1", fed,
               d.effects.damping.feedback.max_alpha = R(-1.0));
    BAD_EFFECT("init: feedback target value -1", fed,
               (d.effects.damping.feedback.target.points = 1,
                d.effects.damping.feedback.target.values[0] = R(-1.0)));
    BAD_EFFECT("init: feedback target.points 9", fed,
               d.effects.damping.feedback.target.points = 9);
    BAD_EFFECT("init: damping.zone_count 5", zoned, d.effects.damping.zone_count = 5);
    BAD_EFFECT("init: damping.zone_count 0xFFFFFFFF", zoned,
               d.effects.damping.zone_count = 0xFFFFFFFFu);
    BAD_EFFECT("init: zone rate -1", zoned, d.effects.damping.zones[0].rate = R(-1.0));
    BAD_EFFECT("init: zone without width in x", zoned,
               d.effects.damping.zones[0].max.x = d.effects.damping.zones[0].min.x);
    BAD_EFFECT("init: zone with max below min in y", zoned,
               d.effects.damping.zones[0].max.y = R(-1.0));
    BAD_EFFECT("init: zone graded toward Z_MIN in 2D", zoned,
               (d.effects.damping.zones[0].ramped = 1,
                d.effects.damping.zones[0].ramp_face = MPM_FACE_Z_MIN));
    BAD_EFFECT("init: second zone rate -1 (zone_count 2)", zoned,
               (d.effects.damping.zone_count = 2, d.effects.damping.zones[1] =
                                                      d.effects.damping.zones[0],
                d.effects.damping.zones[1].rate = R(-1.0)));
    BAD_EFFECT("init: body_force_scale.points 9", g_def2, d.effects.body_force_scale.points = 9);
    BAD_EFFECT("init: body_force_scale times decreasing", g_def2,
               (d.effects.body_force_scale.points = 2,
                d.effects.body_force_scale.times[0] = R(1.0)));
    BAD_EFFECT("init: traction_capacity 2^24 + 1", g_def2,
               d.effects.traction_capacity = (1u << 24) + 1);
    BAD_EFFECT("init: traction_capacity 0xFFFFFFFF", g_def2,
               d.effects.traction_capacity = 0xFFFFFFFFu);
    for (j = 0; j < 3; j++) {
        char name[96];
        snprintf(name, sizeof name, "init: damping.grid value %s", label[j]);
        BAD_EFFECT(name, damped,
                   (d.effects.damping.grid.points = 1,
                    d.effects.damping.grid.values[0] = R(bad[j])));
        snprintf(name, sizeof name, "init: damping.grid time %s", label[j]);
        BAD_EFFECT(name, damped,
                   (d.effects.damping.grid.points = 1, d.effects.damping.grid.times[0] = R(bad[j])));
        snprintf(name, sizeof name, "init: damping.particle value %s", label[j]);
        BAD_EFFECT(name, damped,
                   (d.effects.damping.particle.points = 1,
                    d.effects.damping.particle.values[0] = R(bad[j])));
        snprintf(name, sizeof name, "init: feedback gain %s", label[j]);
        BAD_EFFECT(name, fed, d.effects.damping.feedback.gain = R(bad[j]));
        snprintf(name, sizeof name, "init: feedback target time %s", label[j]);
        BAD_EFFECT(name, fed,
                   (d.effects.damping.feedback.target.points = 1,
                    d.effects.damping.feedback.target.times[0] = R(bad[j])));
        snprintf(name, sizeof name, "init: zone rate %s", label[j]);
        BAD_EFFECT(name, zoned, d.effects.damping.zones[0].rate = R(bad[j]));
        snprintf(name, sizeof name, "init: zone min.x %s", label[j]);
        BAD_EFFECT(name, zoned, d.effects.damping.zones[0].min.x = R(bad[j]));
        snprintf(name, sizeof name, "init: zone max.y %s", label[j]);
        BAD_EFFECT(name, zoned, d.effects.damping.zones[0].max.y = R(bad[j]));
        snprintf(name, sizeof name, "init: body_force.x %s", label[j]);
        BAD_EFFECT(name, g_def2, d.effects.body_force.x = R(bad[j]));
        snprintf(name, sizeof name, "init: body_force.y %s", label[j]);
        BAD_EFFECT(name, g_def2, d.effects.body_force.y = R(bad[j]));
        snprintf(name, sizeof name, "init: body_force.z %s (3D)", label[j]);
        BAD_EFFECT(name, def_3d(), d.effects.body_force.z = R(bad[j]));
        snprintf(name, sizeof name, "init: body_force_gradient[1].x %s", label[j]);
        BAD_EFFECT(name, g_def2, d.effects.body_force_gradient[1].x = R(bad[j]));
        snprintf(name, sizeof name, "init: body_force_gradient[2].z %s (3D)", label[j]);
        BAD_EFFECT(name, def_3d(), d.effects.body_force_gradient[2].z = R(bad[j]));
        snprintf(name, sizeof name, "init: body_force_scale value %s", label[j]);
        BAD_EFFECT(name, g_def2,
                   (d.effects.body_force_scale.points = 1,
                    d.effects.body_force_scale.values[0] = R(bad[j])));
    }
    /* Fixed and flux values of a declared transport that are not finite, on the faces the
     * dimension has (a 2D world does not read its z faces: see below). */
    for (j = 0; j < 3; j++) {
        char name[96];
        snprintf(name, sizeof name, "init: heat fixed X_MIN %s", label[j]);
        BAD_EFFECT(name, heated,
                   (d.effects.heat.faces[MPM_FACE_X_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED,
                    d.effects.heat.faces[MPM_FACE_X_MIN].value = R(bad[j])));
        snprintf(name, sizeof name, "init: heat flux Y_MAX %s", label[j]);
        BAD_EFFECT(name, heated,
                   (d.effects.heat.faces[MPM_FACE_Y_MAX].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX,
                    d.effects.heat.faces[MPM_FACE_Y_MAX].value = R(bad[j])));
        snprintf(name, sizeof name, "init: diffusion fixed X_MAX %s", label[j]);
        BAD_EFFECT(name, diffused,
                   (d.effects.diffusion.faces[MPM_FACE_X_MAX].kind =
                        MPM_SCALAR_BOUNDARY_KIND_FIXED,
                    d.effects.diffusion.faces[MPM_FACE_X_MAX].value = R(bad[j])));
        snprintf(name, sizeof name, "init: diffusion flux Y_MIN %s", label[j]);
        BAD_EFFECT(name, diffused,
                   (d.effects.diffusion.faces[MPM_FACE_Y_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX,
                    d.effects.diffusion.faces[MPM_FACE_Y_MIN].value = R(bad[j])));
        snprintf(name, sizeof name, "init: diffusion flux Z_MAX %s (3D)", label[j]);
        BAD_EFFECT(name, def_3d(),
                   (d.effects.diffusion.declared = 1,
                    d.effects.diffusion.faces[MPM_FACE_Z_MAX].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX,
                    d.effects.diffusion.faces[MPM_FACE_Z_MAX].value = R(bad[j])));
    }
    BAD_EFFECT("init: feedback max_alpha NaN", fed,
               d.effects.damping.feedback.max_alpha = R(NAN));
    BAD_EFFECT("init: feedback max_alpha -inf", fed,
               d.effects.damping.feedback.max_alpha = R(-INFINITY));
#undef BAD_EFFECT

    /* Controls: accepted definitions at the edges. */
#define GOOD_EFFECT(name, base, stmt) \
    d = (base); \
    stmt; \
    ACCEPTED((name), 0, mpm_memory_requirements(&d, &req))
    GOOD_EFFECT("init: damping fields not read when damping is not declared", g_def2,
                (d.effects.damping.grid.points = 99, d.effects.damping.per_particle = 7,
                 d.effects.damping.feedback.declared = 5,
                 d.effects.damping.particle.values[0] = R(NAN)));
    GOOD_EFFECT("init: feedback fields not read when the thermostat is not declared", damped,
                (d.effects.damping.feedback.gain = R(NAN),
                 d.effects.damping.feedback.target.points = 99));
    GOOD_EFFECT("init: feedback max_alpha +inf (unbounded)", fed,
                d.effects.damping.feedback.max_alpha = R(INFINITY));
    GOOD_EFFECT("init: body_force.z NaN in 2D (not read)", g_def2,
                d.effects.body_force.z = R(NAN));
    GOOD_EFFECT("init: negative body_force_scale value", g_def2,
                (d.effects.body_force_scale.points = 1,
                 d.effects.body_force_scale.values[0] = R(-2.0)));
    GOOD_EFFECT("init: schedule of 8 points", damped,
                (d.effects.damping.grid.points = 8, d.effects.damping.grid.times[1] = R(1.0),
                 d.effects.damping.grid.times[2] = R(2.0), d.effects.damping.grid.times[3] = R(3.0),
                 d.effects.damping.grid.times[4] = R(4.0), d.effects.damping.grid.times[5] = R(5.0),
                 d.effects.damping.grid.times[6] = R(6.0), d.effects.damping.grid.times[7] = R(7.0)));
    GOOD_EFFECT("init: traction_capacity 2^24", g_def2, d.effects.traction_capacity = 1u << 24);
    GOOD_EFFECT("init: transport fields not read when heat and diffusion are not declared",
                g_def2,
                (d.effects.heat.sources = 7, d.effects.heat.faces[0].kind = 99,
                 d.effects.heat.faces[1].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED,
                 d.effects.heat.faces[1].value = R(NAN), d.effects.diffusion.sources = 5,
                 d.effects.diffusion.faces[3].kind = 0xFFFFFFFFu,
                 d.effects.diffusion.faces[4].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX,
                 d.effects.diffusion.faces[4].value = R(INFINITY)));
    GOOD_EFFECT("init: a 2D world does not read its z faces' values", heated,
                (d.effects.heat.faces[MPM_FACE_Z_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED,
                 d.effects.heat.faces[MPM_FACE_Z_MIN].value = R(NAN)));
    GOOD_EFFECT("init: the value of an insulated face is not read", heated,
                (d.effects.heat.faces[MPM_FACE_X_MIN].value = R(NAN),
                 d.effects.heat.faces[MPM_FACE_Z_MAX].value = R(-INFINITY)));
    GOOD_EFFECT("init: heat and diffusion with every kind of face and sources", heated,
                (d.effects.heat.faces[MPM_FACE_X_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED,
                 d.effects.heat.faces[MPM_FACE_X_MIN].value = R(-273.0),
                 d.effects.heat.faces[MPM_FACE_X_MAX].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX,
                 d.effects.heat.faces[MPM_FACE_X_MAX].value = R(-1e30),
                 d.effects.heat.sources = 1, d.effects.diffusion.declared = 1,
                 d.effects.diffusion.faces[MPM_FACE_Y_MAX].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX,
                 d.effects.diffusion.faces[MPM_FACE_Y_MAX].value = R(0.0),
                 d.effects.diffusion.sources = 1));
#undef GOOD_EFFECT
}

/* Axisymmetric definitions: the lower x face must be a wall (stick or slip) whose plane is the
 * axis r = 0, origin.x = -margin * cell_size (1 cell for GIMP, cpGIMP and the B-splines, none
 * for linear hats); anything else is MPM_STATUS_INVALID_AXIS. */
static void axisymmetric_def_misuse(void) {
    const MpmWorldDef a = def_axisym();
    MpmWorldDef d;
    MpmMemoryRequirements req, req_plane;

#define BAD_AXIS(name, stmt) \
    d = a; \
    stmt; \
    init_refused((name), MPM_STATUS_INVALID_AXIS, &d)
    BAD_AXIS("init: axisymmetric, origin.x 0 (the axis inside GIMP's margin)",
             d.origin.x = R(0.0));
    BAD_AXIS("init: axisymmetric, origin.x -2 cells", d.origin.x = R(-0.1));
    BAD_AXIS("init: axisymmetric, origin.x half a cell off", d.origin.x = R(-0.025));
    BAD_AXIS("init: axisymmetric, origin.x +1 cell", d.origin.x = R(0.05));
    BAD_AXIS("init: axisymmetric, origin.x 1e-3 cell off", d.origin.x = R(-0.05 + 0.00005));
    BAD_AXIS("init: axisymmetric, origin.x -1e30", d.origin.x = R(-1e30));
    BAD_AXIS("init: axisymmetric, lower x face open", d.faces[MPM_FACE_X_MIN] = MPM_BOUNDARY_OPEN);
    BAD_AXIS("init: axisymmetric, lower x face open and origin.x 0",
             (d.faces[MPM_FACE_X_MIN] = MPM_BOUNDARY_OPEN, d.origin.x = R(0.0)));
    BAD_AXIS("init: axisymmetric linear, origin.x -1 cell (linear hats have no margin)",
             d.shape = MPM_SHAPE_LINEAR);
    BAD_AXIS("init: axisymmetric linear, lower x face open",
             (d.shape = MPM_SHAPE_LINEAR, d.origin.x = R(0.0),
              d.faces[MPM_FACE_X_MIN] = MPM_BOUNDARY_OPEN));
    BAD_AXIS("init: axisymmetric quadratic B-spline, origin.x 0",
             (d.shape = MPM_SHAPE_QUADRATIC_BSPLINE, d.origin.x = R(0.0)));
    BAD_AXIS("init: axisymmetric cubic B-spline, origin.x 0",
             (d.shape = MPM_SHAPE_CUBIC_BSPLINE, d.origin.x = R(0.0)));
    BAD_AXIS("init: axisymmetric cpGIMP, origin.x 0",
             (d.shape = MPM_SHAPE_CP_GIMP, d.origin.x = R(0.0)));
    BAD_AXIS("init: axisymmetric without effects, origin.x 0",
             (d.effects = g_def2.effects, d.origin.x = R(0.0)));
#undef BAD_AXIS
    /* A non-finite origin is named as such, before the axis. */
    d = a;
    d.origin.x = R(NAN);
    init_refused("init: axisymmetric, origin.x NaN", MPM_STATUS_NON_FINITE_DEFINITION, &d);

    /* Controls: walls at the axis, for every family. */
#define GOOD_AXIS(name, stmt) \
    d = a; \
    stmt; \
    ACCEPTED((name), 0, mpm_memory_requirements(&d, &req))
    GOOD_AXIS("init: axisymmetric GIMP, origin.x -1 cell, slip at the axis", (void)0);
    GOOD_AXIS("init: axisymmetric, stick at the axis",
              d.faces[MPM_FACE_X_MIN] = MPM_BOUNDARY_STICK);
    GOOD_AXIS("init: axisymmetric, upper x face open", d.faces[MPM_FACE_X_MAX] = MPM_BOUNDARY_OPEN);
    GOOD_AXIS("init: axisymmetric, origin.y anywhere", d.origin.y = R(-7.5));
    GOOD_AXIS("init: axisymmetric, origin.x off by round-off (1e-5 cell)",
              d.origin.x = R(-0.05 - 0.0000005));
    GOOD_AXIS("init: axisymmetric linear, origin.x 0",
              (d.shape = MPM_SHAPE_LINEAR, d.origin.x = R(0.0)));
    GOOD_AXIS("init: axisymmetric quadratic B-spline, origin.x -1 cell",
              d.shape = MPM_SHAPE_QUADRATIC_BSPLINE);
    GOOD_AXIS("init: axisymmetric cubic B-spline, origin.x -1 cell",
              d.shape = MPM_SHAPE_CUBIC_BSPLINE);
    GOOD_AXIS("init: axisymmetric cpGIMP, origin.x -1 cell", d.shape = MPM_SHAPE_CP_GIMP);
    GOOD_AXIS("init: axisymmetric APIC", d.transfer = MPM_TRANSFER_APIC);
    GOOD_AXIS("init: axisymmetric XPIC(3)", d.transfer = MPM_TRANSFER_XPIC + 256u * 3u);
    GOOD_AXIS("init: axisymmetric FMPM(2)", d.transfer = MPM_TRANSFER_FMPM + 256u * 2u);
    d = a;
    d.transfer = MPM_TRANSFER_FLIP_MOMENTUM;
    init_refused("init: axisymmetric FLIP momentum", MPM_STATUS_INVALID_TRANSFER, &d);
    GOOD_AXIS("init: axisymmetric without effects", d.effects = g_def2.effects);
#undef GOOD_AXIS
    d = a;
    d.dimension = MPM_DIMENSION_PLANE2D;
    ACCEPTED("init: the axisymmetric definition as plane strain", 0,
             mpm_memory_requirements(&d, &req_plane));
    ACCEPTED("init: the axisymmetric definition", 0, mpm_memory_requirements(&a, &req));
    expect_true("init: the hoop column takes memory", req.bytes > req_plane.bytes);
}

static void init_misuse(void) {
    MpmWorldDef d;
    MpmMemoryRequirements req;
    size_t total;
    unsigned k;
    static const uint32_t bad_enum[] = {0xFFFFFFFFu, 0x80000000u, 7u};

    if (mpm_memory_requirements(&g_def2, &g_init_req) != MPM_STATUS_OK) {
        fail("init: setup", "mpm_memory_requirements refused the 2D definition");
    }
    total = g_init_req.bytes + 2 * g_init_req.align;
    g_init_mem = block_new(g_init_req.bytes, g_init_req.align, g_init_req.align);

    /* The buffer itself. */
    memset(g_init_mem.raw, PATTERN, total);
    REFUSED("init: buffer one byte too small", MPM_STATUS_BUFFER_TOO_SMALL,
            mpm_world_init(&g_def2, g_init_mem.at, g_init_req.bytes - 1, OUT(MpmWorld *)));
    REFUSED("init: buffer of 0 bytes", MPM_STATUS_BUFFER_TOO_SMALL,
            mpm_world_init(&g_def2, g_init_mem.at, 0, OUT(MpmWorld *)));
    REFUSED("init: buffer misaligned by 1 byte", MPM_STATUS_BUFFER_MISALIGNED,
            mpm_world_init(&g_def2, g_init_mem.at + 1, g_init_req.bytes, OUT(MpmWorld *)));
    REFUSED("init: buffer misaligned by 8 bytes", MPM_STATUS_BUFFER_MISALIGNED,
            mpm_world_init(&g_def2, g_init_mem.at + 8, g_init_req.bytes, OUT(MpmWorld *)));
    REFUSED("init: buffer misaligned by align / 2", MPM_STATUS_BUFFER_MISALIGNED,
            mpm_world_init(&g_def2, g_init_mem.at + g_init_req.align / 2, g_init_req.bytes,
                           OUT(MpmWorld *)));
    expect_true("init: refused buffers left the memory untouched",
                pattern_intact(g_init_mem.raw, total));

    /* Definitions that did not come from the default function. */
    memset(&d, 0, sizeof d);
    init_refused("init: zeroed MpmWorldDef", MPM_STATUS_DEF_NOT_FROM_DEFAULT, &d);
    d = g_def2;
    d.internal_cookie += 1;
    init_refused("init: cookie changed", MPM_STATUS_DEF_NOT_FROM_DEFAULT, &d);
    d = g_def2;
    d.internal_cookie = 0;
    init_refused("init: cookie zeroed", MPM_STATUS_DEF_NOT_FROM_DEFAULT, &d);
    /* The other precision's cookie differs in the bits of sizeof(mpm_real). */
    d = g_def2;
    d.internal_cookie ^= 4u ^ 8u;
    init_refused("init: cookie of the other precision", MPM_STATUS_DEF_NOT_FROM_DEFAULT, &d);

    /* Enum fields out of range. */
    for (k = 0; k < sizeof bad_enum / sizeof bad_enum[0]; k++) {
        char name[96];
        int f;
        d = g_def2;
        d.dimension = bad_enum[k];
        snprintf(name, sizeof name, "init: dimension %u", (unsigned)bad_enum[k]);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = g_def2;
        d.shape = bad_enum[k];
        snprintf(name, sizeof name, "init: shape %u", (unsigned)bad_enum[k]);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        d = g_def2;
        d.update_order = bad_enum[k];
        snprintf(name, sizeof name, "init: update_order %u", (unsigned)bad_enum[k]);
        init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        for (f = 0; f < 6; f++) {
            d = g_def2;
            d.faces[f] = bad_enum[k];
            snprintf(name, sizeof name, "init: faces[%d] %u", f, (unsigned)bad_enum[k]);
            init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        }
    }
    d = g_def2;
    d.dimension = 0;
    init_refused("init: dimension 0", MPM_STATUS_INVALID_ENUM, &d);
    d.dimension = 1;
    init_refused("init: dimension 1", MPM_STATUS_INVALID_ENUM, &d);
    d.dimension = 5;
    init_refused("init: dimension 5", MPM_STATUS_INVALID_ENUM, &d);
    d = g_def2;
    d.shape = 5;
    init_refused("init: shape 5", MPM_STATUS_INVALID_ENUM, &d);
    d.shape = MPM_SHAPE_CP_GIMP;
    ACCEPTED("init: shape 4 (cpGIMP)", 0, mpm_memory_requirements(&d, &req));
    d.cells[0] = 3;
    init_refused("init: cpGIMP, cells[0] 3 (below its minimum, as GIMP's)",
                 MPM_STATUS_INVALID_CELL_COUNT, &d);
    d = g_def2;
    d.update_order = 3;
    init_refused("init: update_order 3", MPM_STATUS_INVALID_ENUM, &d);
    {
        int f;
        for (f = 0; f < 6; f++) {
            char name[64];
            d = g_def2;
            d.faces[f] = 4;
            snprintf(name, sizeof name, "init: faces[%d] 4", f);
            init_refused(name, MPM_STATUS_INVALID_ENUM, &d);
        }
        /* Periodic faces come in pairs, without a wall's friction or velocity. */
        for (f = 0; f < 4; f++) {
            char name[64];
            d = g_def2;
            d.faces[f] = MPM_BOUNDARY_PERIODIC;
            snprintf(name, sizeof name, "init: faces[%d] periodic alone", f);
            init_refused(name, MPM_STATUS_INVALID_BOUNDARY, &d);
        }
        d = g_def2;
        d.faces[MPM_FACE_X_MIN] = d.faces[MPM_FACE_X_MAX] = MPM_BOUNDARY_PERIODIC;
        ACCEPTED("init: x faces periodic", 0, mpm_memory_requirements(&d, &req));
        d.wall_friction[MPM_FACE_X_MAX] = (mpm_real)0.3;
        init_refused("init: periodic face with friction", MPM_STATUS_INVALID_BOUNDARY, &d);
    }
    axisymmetric_def_misuse();

    /* Non-finite and out-of-range values. */
#define BAD_DEF(name, field, value, want) \
    d = g_def2; \
    d.field = (value); \
    init_refused((name), (want), &d)
    BAD_DEF("init: cell_size NaN", cell_size, R(NAN), MPM_STATUS_INVALID_CELL_SIZE);
    BAD_DEF("init: cell_size +inf", cell_size, R(INFINITY), MPM_STATUS_INVALID_CELL_SIZE);
    BAD_DEF("init: cell_size 0", cell_size, R(0.0), MPM_STATUS_INVALID_CELL_SIZE);
    BAD_DEF("init: cell_size -1", cell_size, R(-1.0), MPM_STATUS_INVALID_CELL_SIZE);
    BAD_DEF("init: origin.x NaN", origin.x, R(NAN), MPM_STATUS_NON_FINITE_DEFINITION);
    BAD_DEF("init: origin.y -inf", origin.y, R(-INFINITY), MPM_STATUS_NON_FINITE_DEFINITION);
    BAD_DEF("init: gravity.x NaN", gravity.x, R(NAN), MPM_STATUS_NON_FINITE_DEFINITION);
    BAD_DEF("init: gravity.y +inf", gravity.y, R(INFINITY), MPM_STATUS_NON_FINITE_DEFINITION);
    BAD_DEF("init: cells[0] 3 (below the GIMP minimum)", cells[0], 3,
            MPM_STATUS_INVALID_CELL_COUNT);
    BAD_DEF("init: cells[1] 0", cells[1], 0, MPM_STATUS_INVALID_CELL_COUNT);
    BAD_DEF("init: particle_capacity 0", particle_capacity, 0, MPM_STATUS_INVALID_CAPACITY);
    BAD_DEF("init: material_capacity 0", material_capacity, 0, MPM_STATUS_INVALID_CAPACITY);
    BAD_DEF("init: flip_beta NaN", flip_beta, R(NAN), MPM_STATUS_INVALID_FLIP_BETA);
    BAD_DEF("init: flip_beta -0.5", flip_beta, R(-0.5), MPM_STATUS_INVALID_FLIP_BETA);
    BAD_DEF("init: flip_beta 1.5", flip_beta, R(1.5), MPM_STATUS_INVALID_FLIP_BETA);
    BAD_DEF("init: pic_rate -1", pic_rate, R(-1.0), MPM_STATUS_INVALID_FLIP_BETA);
    BAD_DEF("init: pic_rate NaN", pic_rate, R(NAN), MPM_STATUS_INVALID_FLIP_BETA);
    BAD_DEF("init: pic_rate inf", pic_rate, R(INFINITY), MPM_STATUS_INVALID_FLIP_BETA);
    BAD_DEF("init: cfl NaN", cfl, R(NAN), MPM_STATUS_INVALID_CFL);
    BAD_DEF("init: cfl +inf", cfl, R(INFINITY), MPM_STATUS_INVALID_CFL);
    BAD_DEF("init: cfl 0", cfl, R(0.0), MPM_STATUS_INVALID_CFL);
    BAD_DEF("init: cfl 2", cfl, R(2.0), MPM_STATUS_INVALID_CFL);
    BAD_DEF("init: exp_terms 0", exp_terms, 0, MPM_STATUS_INVALID_EXP_TERMS);
    BAD_DEF("init: exp_terms 9", exp_terms, 9, MPM_STATUS_INVALID_EXP_TERMS);
    BAD_DEF("init: particles_per_cell 0", particles_per_cell, 0,
            MPM_STATUS_INVALID_PARTICLES_PER_CELL);
    BAD_DEF("init: particles_per_cell 9", particles_per_cell, 9,
            MPM_STATUS_INVALID_PARTICLES_PER_CELL);
#undef BAD_DEF

    effects_def_misuse();

    /* Control: the same memory takes a world of the definition read back from the 2D world
     * (the cookie survives mpm_world_get_def). */
    memset(g_init_mem.raw, PATTERN, total);
    if (mpm_world_get_def(g_w2, &d) != MPM_STATUS_OK) {
        fail("init: control", "mpm_world_get_def refused the 2D world");
    }
    {
        MpmWorld *w = NULL;
        MpmStatus s = mpm_world_init(&d, g_init_mem.at, g_init_req.bytes, &w);
        ACCEPTED("init: control init with the definition from mpm_world_get_def", 0, s);
        expect_true("init: control world is at the memory's address",
                    (void *)w == (void *)g_init_mem.at);
        expect_true("init: control init wrote the memory",
                    !pattern_intact(g_init_mem.at, g_init_req.bytes));
    }
    free(g_init_mem.raw);
}

/* mpm_world_open on copies of the 2D world: refused, and the copy's bytes untouched. */
static Block g_copy;

static void open_refused(const char *name, MpmStatus want, void *memory, size_t len) {
    const size_t span = g_w2_bytes + 8;
    uint64_t before = fnv1a(g_copy.at, span);
    REFUSED(name, want, mpm_world_open(memory, len, OUT(MpmWorld *)));
    if (fnv1a(g_copy.at, span) != before) {
        fail(name, "the refused open changed the memory");
    }
}

static void open_misuse(void) {
    MpmWorld *w = NULL;
    size_t k;

    g_copy = block_new(g_w2_bytes, 64, 64);
    memset(g_copy.at, 0, g_w2_bytes + 8);
    memcpy(g_copy.at, g_w2, g_w2_bytes);
    open_refused("open: copy one byte short", MPM_STATUS_BUFFER_TOO_SMALL, g_copy.at,
                 g_w2_bytes - 1);
    open_refused("open: 8 bytes (less than a header)", MPM_STATUS_BUFFER_TOO_SMALL, g_copy.at, 8);
    open_refused("open: 0 bytes", MPM_STATUS_BUFFER_TOO_SMALL, g_copy.at, 0);

    /* The same bytes 8 bytes further on. */
    memmove(g_copy.at + 8, g_copy.at, g_w2_bytes);
    open_refused("open: copy misaligned by 8 bytes", MPM_STATUS_BUFFER_MISALIGNED,
                 g_copy.at + 8, g_w2_bytes);
    memmove(g_copy.at, g_copy.at + 8, g_w2_bytes);

    /* A header whose first word (the magic number) is damaged. */
    for (k = 0; k < 8; k++) {
        g_copy.at[k] ^= 0xFF;
    }
    open_refused("open: damaged header", MPM_STATUS_NOT_A_WORLD, g_copy.at, g_w2_bytes);
    for (k = 0; k < 8; k++) {
        g_copy.at[k] ^= 0xFF;
    }

    memset(g_copy.at, 0, g_w2_bytes);
    open_refused("open: zeroed memory", MPM_STATUS_NOT_A_WORLD, g_copy.at, g_w2_bytes);

    /* Control: an intact copy opens, at its own address, with the original's bytes. */
    memcpy(g_copy.at, g_w2, g_w2_bytes);
    ACCEPTED("open: control open of an intact copy", 0,
             mpm_world_open(g_copy.at, g_w2_bytes, &w));
    expect_true("open: control world is at the copy's address", (void *)w == (void *)g_copy.at);
    expect_true("open: control copy hashes like the original",
                world_hash(w) == world_hash(g_w2));
    free(g_copy.raw);
}

/* mpm_world_add_material: definitions, enum, parameters. */
static void material_misuse(void) {
    MpmMaterialDef m;
    static const uint32_t bad_model[] = {7u, 99u, 0x80000000u, 0xFFFFFFFFu};
    unsigned k;

    memset(&m, 0, sizeof m);
    REFUSED("material: zeroed MpmMaterialDef", MPM_STATUS_DEF_NOT_FROM_DEFAULT,
            mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    m = mpm_material_def_default();
    m.internal_cookie += 1;
    REFUSED("material: cookie changed", MPM_STATUS_DEF_NOT_FROM_DEFAULT,
            mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    m = mpm_material_def_default();
    m.internal_cookie ^= 4u ^ 8u;
    REFUSED("material: cookie of the other precision", MPM_STATUS_DEF_NOT_FROM_DEFAULT,
            mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    {
        /* A world definition's cookie is not a material's. */
        MpmWorldDef wd = mpm_world_def_default();
        m = mpm_material_def_default();
        m.internal_cookie = wd.internal_cookie;
        REFUSED("material: a world definition's cookie", MPM_STATUS_DEF_NOT_FROM_DEFAULT,
                mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    }

    for (k = 0; k < sizeof bad_model / sizeof bad_model[0]; k++) {
        char name[64];
        m = mpm_material_def_default();
        m.model = bad_model[k];
        snprintf(name, sizeof name, "material: model %u", (unsigned)bad_model[k]);
        REFUSED(name, MPM_STATUS_INVALID_ENUM, mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
        m = mpm_material_def_default();
        m.friction_fit = bad_model[k] - 3;
        snprintf(name, sizeof name, "material: friction fit %u", (unsigned)m.friction_fit);
        REFUSED(name, MPM_STATUS_INVALID_ENUM, mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    }

#define BAD_MAT(name, field, value) \
    m = mpm_material_def_default(); \
    m.field = (value); \
    REFUSED((name), MPM_STATUS_INVALID_MATERIAL, mpm_world_add_material(g_w2, &m, OUT(uint32_t)))
    BAD_MAT("material: youngs_modulus NaN", youngs_modulus, R(NAN));
    BAD_MAT("material: youngs_modulus +inf", youngs_modulus, R(INFINITY));
    BAD_MAT("material: youngs_modulus 0", youngs_modulus, R(0.0));
    BAD_MAT("material: youngs_modulus -1e6", youngs_modulus, R(-1e6));
    BAD_MAT("material: poisson_ratio NaN", poisson_ratio, R(NAN));
    BAD_MAT("material: poisson_ratio -inf", poisson_ratio, R(-INFINITY));
    BAD_MAT("material: poisson_ratio 0.5", poisson_ratio, R(0.5));
    BAD_MAT("material: poisson_ratio -1", poisson_ratio, R(-1.0));
    BAD_MAT("material: density NaN", density, R(NAN));
    BAD_MAT("material: density +inf", density, R(INFINITY));
    BAD_MAT("material: density 0", density, R(0.0));
    BAD_MAT("material: density -1000", density, R(-1000.0));
    BAD_MAT("material: heat_capacity NaN", heat_capacity, R(NAN));
    BAD_MAT("material: heat_capacity +inf", heat_capacity, R(INFINITY));
    BAD_MAT("material: heat_capacity 0", heat_capacity, R(0.0));
    BAD_MAT("material: heat_capacity -1000", heat_capacity, R(-1000.0));
    BAD_MAT("material: conductivity NaN", conductivity, R(NAN));
    BAD_MAT("material: conductivity +inf", conductivity, R(INFINITY));
    BAD_MAT("material: conductivity -1", conductivity, R(-1.0));
    BAD_MAT("material: conductivity -1e-30", conductivity, R(-1e-30));
    BAD_MAT("material: diffusivity NaN", diffusivity, R(NAN));
    BAD_MAT("material: diffusivity +inf", diffusivity, R(INFINITY));
    BAD_MAT("material: diffusivity -1", diffusivity, R(-1.0));
    BAD_MAT("material: diffusivity -inf", diffusivity, R(-INFINITY));
    BAD_MAT("material: thermal_expansion NaN", thermal_expansion, R(NAN));
    BAD_MAT("material: thermal_expansion +inf", thermal_expansion, R(INFINITY));
    BAD_MAT("material: thermal_expansion -inf", thermal_expansion, R(-INFINITY));
    BAD_MAT("material: reference_temperature NaN", reference_temperature, R(NAN));
    BAD_MAT("material: reference_temperature +inf", reference_temperature, R(INFINITY));
    BAD_MAT("material: reference_temperature -inf", reference_temperature, R(-INFINITY));
    BAD_MAT("material: swelling NaN", swelling, R(NAN));
    BAD_MAT("material: swelling +inf", swelling, R(INFINITY));
    BAD_MAT("material: swelling -inf", swelling, R(-INFINITY));
    BAD_MAT("material: reference_concentration NaN", reference_concentration, R(NAN));
    BAD_MAT("material: reference_concentration +inf", reference_concentration, R(INFINITY));
    BAD_MAT("material: reference_concentration -inf", reference_concentration, R(-INFINITY));
    BAD_MAT("material: viscosity NaN", viscosity, R(NAN));
    BAD_MAT("material: viscosity -1", viscosity, R(-1.0));
    BAD_MAT("material: viscosity +inf", viscosity, R(INFINITY));
    BAD_MAT("material: bulk viscosity NaN", bulk_viscosity, R(NAN));
    BAD_MAT("material: bulk viscosity -1", bulk_viscosity, R(-1.0));
    BAD_MAT("material: bulk viscosity +inf", bulk_viscosity, R(INFINITY));
    BAD_MAT("material: volume relaxation NaN", volume_relaxation, R(NAN));
    BAD_MAT("material: volume relaxation -1", volume_relaxation, R(-1.0));
    BAD_MAT("material: volume relaxation +inf", volume_relaxation, R(INFINITY));
    BAD_MAT("material: bulk_modulus 0", bulk_modulus, R(0.0));
    BAD_MAT("material: bulk_modulus NaN", bulk_modulus, R(NAN));
    BAD_MAT("material: pressure_exponent 0.5", pressure_exponent, R(0.5));
    BAD_MAT("material: pressure_exponent +inf", pressure_exponent, R(INFINITY));
    BAD_MAT("material: yield_stress 0", yield_stress, R(0.0));
    BAD_MAT("material: yield_stress NaN", yield_stress, R(NAN));
    BAD_MAT("material: hardening_modulus -1", hardening_modulus, R(-1.0));
    BAD_MAT("material: friction_angle 90", friction_angle, R(90.0));
    BAD_MAT("material: friction_angle -1", friction_angle, R(-1.0));
    BAD_MAT("material: friction_angle NaN", friction_angle, R(NAN));
    BAD_MAT("material: cohesion -1", cohesion, R(-1.0));
    BAD_MAT("material: critical_compression 0", critical_compression, R(0.0));
    BAD_MAT("material: critical_compression 1", critical_compression, R(1.0));
    BAD_MAT("material: critical_stretch 0", critical_stretch, R(0.0));
    BAD_MAT("material: critical_stretch +inf", critical_stretch, R(INFINITY));
    BAD_MAT("material: hardening_coefficient -1", hardening_coefficient, R(-1.0));
    BAD_MAT("material: hardening_coefficient past 100", hardening_coefficient, R(100.5));
#undef BAD_MAT
    /* A cohesion needs a friction angle (the apex of the yield surface is c cot(phi)). */
    m = mpm_material_def_default();
    m.model = MPM_MATERIAL_MODEL_DRUCKER_PRAGER;
    m.friction_angle = R(0.0);
    m.cohesion = R(1e3);
    REFUSED("material: cohesion without friction", MPM_STATUS_INVALID_MATERIAL,
            mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    /* The plastic models keep a history the definition must declare. */
    for (k = MPM_MATERIAL_MODEL_VON_MISES; k <= MPM_MATERIAL_MODEL_SNOW; k++) {
        char name[64];
        m = mpm_material_def_default();
        m.model = k;
        snprintf(name, sizeof name, "material: plastic model %u undeclared", k);
        REFUSED(name, MPM_STATUS_EFFECT_NOT_DECLARED,
                mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    }
    /* The same on the axisymmetric world, which declares heat and diffusion. */
    m = mpm_material_def_default();
    m.thermal_expansion = R(NAN);
    REFUSED("material: thermal_expansion NaN (axisymmetric, heat declared)",
            MPM_STATUS_INVALID_MATERIAL, mpm_world_add_material(g_wa, &m, OUT(uint32_t)));
    m = mpm_material_def_default();
    m.swelling = R(INFINITY);
    REFUSED("material: swelling +inf (axisymmetric, diffusion declared)",
            MPM_STATUS_INVALID_MATERIAL, mpm_world_add_material(g_wa, &m, OUT(uint32_t)));
    /* Any finite value is a material, negative and large ones included. */
    {
        uint32_t id = 0xFFFFFFFFu;
        m = mpm_material_def_default();
        m.thermal_expansion = R(-1e-3);
        m.reference_temperature = R(-1e6);
        m.swelling = R(-2.0);
        m.reference_concentration = R(1e6);
        ACCEPTED("material: negative and large expansion, swelling and references (axisymmetric)",
                 1, mpm_world_add_material(g_wa, &m, &id));
        expect_true("material: the second axisymmetric material has id 1", id == 1);
    }
}

/* Current particle count of a world. */
static size_t particle_count(const MpmWorld *w) {
    MpmDiagnostics d;
    if (mpm_world_diagnostics(w, &d) != MPM_STATUS_OK) {
        fail("particle_count", "mpm_world_diagnostics refused a world");
    }
    return d.particle_count;
}

/* mpm_world_add_particles: count, values, materials, positions. */
static void particles_misuse(void) {
    Batch b;
    MpmParticleArrays a;
    size_t remaining = g_def2.particle_capacity - particle_count(g_w2);
    int k;

    /* A count above the remaining capacity is refused before any array is read: the arrays
     * hold one value each (AddressSanitizer would see a read past them in instrumented
     * code), and below they point into a page that cannot be read at all. */
    {
        mpm_real *one_real[8];
        uint32_t *one_id = (uint32_t *)malloc(sizeof(uint32_t));
        MpmParticleArrays s;
        for (k = 0; k < 8; k++) {
            one_real[k] = (mpm_real *)malloc(sizeof(mpm_real));
            if (one_real[k] == NULL) {
                fail("particles: setup", "out of memory");
            }
            *one_real[k] = R(0.25);
        }
        if (one_id == NULL) {
            fail("particles: setup", "out of memory");
        }
        *one_id = 0;
        for (k = 0; k < 3; k++) {
            s.position[k] = one_real[k];
            s.velocity[k] = one_real[3 + k];
        }
        s.mass = one_real[6];
        s.volume = one_real[7];
        s.material = one_id;
        REFUSED("particles: count remaining + 1 with 1-value arrays",
                MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
                mpm_world_add_particles(g_w2, &s, remaining + 1, OUT(MpmIdRange)));
        REFUSED("particles: count SIZE_MAX with 1-value arrays",
                MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
                mpm_world_add_particles(g_w2, &s, (size_t)-1, OUT(MpmIdRange)));
        REFUSED("particles: count capacity + 1 with 1-value arrays",
                MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
                mpm_world_add_particles(g_w2, &s, (size_t)g_def2.particle_capacity + 1,
                                        OUT(MpmIdRange)));
        for (k = 0; k < 8; k++) {
            free(one_real[k]);
        }
        free(one_id);
    }
#ifdef MISUSE_HAVE_MMAN
    {
        long page = sysconf(_SC_PAGESIZE);
        void *p = mmap(NULL, (size_t)page, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        MpmParticleArrays s;
        if (p == MAP_FAILED) {
            fail("particles: setup", "mmap failed");
        }
        for (k = 0; k < 3; k++) {
            s.position[k] = (const mpm_real *)p;
            s.velocity[k] = (const mpm_real *)p;
        }
        s.mass = (const mpm_real *)p;
        s.volume = (const mpm_real *)p;
        s.material = (const uint32_t *)p;
        REFUSED("particles: count remaining + 1 with arrays in a no-access page",
                MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
                mpm_world_add_particles(g_w2, &s, remaining + 1, OUT(MpmIdRange)));
        REFUSED("particles: count SIZE_MAX with arrays in a no-access page",
                MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
                mpm_world_add_particles(g_w2, &s, (size_t)-1, OUT(MpmIdRange)));
        munmap(p, (size_t)page);
    }
#endif

    /* Bad values in the last of three particles: all or nothing. */
#define BAD_PARTICLE(name, stmt, want) \
    batch_fill(&b, 3, 0.2, 0.2, 0.0); \
    stmt; \
    a = arrays_of(&b); \
    REFUSED((name), (want), mpm_world_add_particles(g_w2, &a, 3, OUT(MpmIdRange)))
    {
        const double bad[3] = {NAN, INFINITY, -INFINITY};
        const char *label[3] = {"NaN", "+inf", "-inf"};
        int j;
        for (j = 0; j < 3; j++) {
            char name[96];
            for (k = 0; k < 2; k++) {
                snprintf(name, sizeof name, "particles: position[%d] %s", k, label[j]);
                BAD_PARTICLE(name, b.x[k][2] = R(bad[j]), MPM_STATUS_NON_FINITE_INPUT);
                snprintf(name, sizeof name, "particles: velocity[%d] %s", k, label[j]);
                BAD_PARTICLE(name, b.v[k][2] = R(bad[j]), MPM_STATUS_NON_FINITE_INPUT);
            }
            snprintf(name, sizeof name, "particles: mass %s", label[j]);
            BAD_PARTICLE(name, b.mass[2] = R(bad[j]), MPM_STATUS_NON_FINITE_INPUT);
            snprintf(name, sizeof name, "particles: volume %s", label[j]);
            BAD_PARTICLE(name, b.volume[2] = R(bad[j]), MPM_STATUS_NON_FINITE_INPUT);
        }
    }
    BAD_PARTICLE("particles: mass 0", b.mass[2] = R(0.0), MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME);
    BAD_PARTICLE("particles: mass -0", b.mass[2] = R(-0.0),
                 MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME);
    BAD_PARTICLE("particles: mass -1", b.mass[2] = R(-1.0),
                 MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME);
    BAD_PARTICLE("particles: volume 0", b.volume[2] = R(0.0),
                 MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME);
    BAD_PARTICLE("particles: volume -1e-6", b.volume[2] = R(-1e-6),
                 MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME);
    BAD_PARTICLE("particles: material 1 (only 0 exists)", b.material[2] = 1,
                 MPM_STATUS_UNKNOWN_MATERIAL);
    BAD_PARTICLE("particles: material 0xFFFFFFFF", b.material[2] = 0xFFFFFFFFu,
                 MPM_STATUS_UNKNOWN_MATERIAL);
    BAD_PARTICLE("particles: x -1 (outside the grid)", b.x[0][2] = R(-1.0),
                 MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
    BAD_PARTICLE("particles: x 10 (outside the grid)", b.x[0][2] = R(10.0),
                 MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
    BAD_PARTICLE("particles: x 0.01 (in the boundary margin)", b.x[0][2] = R(0.01),
                 MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
    BAD_PARTICLE("particles: y 0.99 (in the boundary margin)", b.x[1][2] = R(0.99),
                 MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
    BAD_PARTICLE("particles: y 1e30", b.x[1][2] = R(1e30), MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
#undef BAD_PARTICLE

    /* 3D: the z column is read and checked. */
#define BAD_PARTICLE_3D(name, stmt, want) \
    batch_fill(&b, 3, 0.2, 0.2, 0.2); \
    stmt; \
    a = arrays_of(&b); \
    REFUSED((name), (want), mpm_world_add_particles(g_w3, &a, 3, OUT(MpmIdRange)))
    BAD_PARTICLE_3D("particles 3D: position[2] NaN", b.x[2][2] = R(NAN),
                    MPM_STATUS_NON_FINITE_INPUT);
    BAD_PARTICLE_3D("particles 3D: velocity[2] +inf", b.v[2][2] = R(INFINITY),
                    MPM_STATUS_NON_FINITE_INPUT);
    BAD_PARTICLE_3D("particles 3D: z 0.01 (in the boundary margin)", b.x[2][2] = R(0.01),
                    MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
    BAD_PARTICLE_3D("particles 3D: z 1 (outside the grid)", b.x[2][2] = R(1.0),
                    MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
#undef BAD_PARTICLE_3D
}

/* Seeding regions. */
static void fill_misuse(void) {
    MpmVec3 z = v3(0, 0, 0);
    MpmVec3 lo = v3(0.2, 0.6, 0), hi = v3(0.25, 0.65, 0);
    MpmVec3 c = v3(0.3, 0.7, 0);
    MpmVec3 c3 = v3(0.2, 0.2, 0.2);
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    const char *label[3] = {"NaN", "+inf", "-inf"};
    int j;

    for (j = 0; j < 3; j++) {
        char name[96];
        MpmVec3 p;
        p = lo;
        p.x = R(bad[j]);
        snprintf(name, sizeof name, "fill_box: min.x %s", label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_fill_box(g_w2, p, hi, 0, z, OUT(MpmIdRange)));
        p = hi;
        p.y = R(bad[j]);
        snprintf(name, sizeof name, "fill_box: max.y %s", label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_fill_box(g_w2, lo, p, 0, z, OUT(MpmIdRange)));
        p = z;
        p.x = R(bad[j]);
        snprintf(name, sizeof name, "fill_box: velocity.x %s", label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_fill_box(g_w2, lo, hi, 0, p, OUT(MpmIdRange)));
        p = c;
        p.y = R(bad[j]);
        snprintf(name, sizeof name, "fill_disk: center.y %s", label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_fill_disk(g_w2, p, R(0.03), 0, z, OUT(MpmIdRange)));
        snprintf(name, sizeof name, "fill_disk: radius %s", label[j]);
        REFUSED(name, MPM_STATUS_INVALID_REGION,
                mpm_world_fill_disk(g_w2, c, R(bad[j]), 0, z, OUT(MpmIdRange)));
        p = z;
        p.y = R(bad[j]);
        snprintf(name, sizeof name, "fill_disk: velocity.y %s", label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_fill_disk(g_w2, c, R(0.03), 0, p, OUT(MpmIdRange)));
        p = c3;
        p.z = R(bad[j]);
        snprintf(name, sizeof name, "fill_sphere: center.z %s", label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_fill_sphere(g_w3, p, R(0.03), 0, z, OUT(MpmIdRange)));
        snprintf(name, sizeof name, "fill_sphere: radius %s", label[j]);
        REFUSED(name, MPM_STATUS_INVALID_REGION,
                mpm_world_fill_sphere(g_w3, c3, R(bad[j]), 0, z, OUT(MpmIdRange)));
        p = z;
        p.z = R(bad[j]);
        snprintf(name, sizeof name, "fill_sphere: velocity.z %s", label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_fill_sphere(g_w3, c3, R(0.03), 0, p, OUT(MpmIdRange)));
    }
    REFUSED("fill_box: min.x > max.x", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_box(g_w2, v3(0.3, 0.6, 0), v3(0.2, 0.65, 0), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_box: min.y > max.y", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_box(g_w2, v3(0.2, 0.7, 0), v3(0.25, 0.6, 0), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_box 3D: min.z > max.z", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_box(g_w3, v3(0.1, 0.1, 0.3), v3(0.2, 0.2, 0.2), 0, z,
                               OUT(MpmIdRange)));
    REFUSED("fill_disk: radius 0", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_disk(g_w2, c, R(0.0), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_disk: radius -0.03", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_disk(g_w2, c, R(-0.03), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_sphere: radius 0", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_sphere(g_w3, c3, R(0.0), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_box: unknown material 1", MPM_STATUS_UNKNOWN_MATERIAL,
            mpm_world_fill_box(g_w2, lo, hi, 1, z, OUT(MpmIdRange)));
    REFUSED("fill_disk: unknown material 0xFFFFFFFF", MPM_STATUS_UNKNOWN_MATERIAL,
            mpm_world_fill_disk(g_w2, c, R(0.03), 0xFFFFFFFFu, z, OUT(MpmIdRange)));
    REFUSED("fill_sphere: unknown material 1", MPM_STATUS_UNKNOWN_MATERIAL,
            mpm_world_fill_sphere(g_w3, c3, R(0.03), 1, z, OUT(MpmIdRange)));
    REFUSED("fill_box: reaching into the boundary margin", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_box(g_w2, v3(0.0, 0.6, 0), v3(0.1, 0.65, 0), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_box: far larger than the grid", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_box(g_w2, v3(-1e30, -1e30, 0), v3(1e30, 1e30, 0), 0, z,
                               OUT(MpmIdRange)));
    REFUSED("fill_disk: partly outside the grid", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_disk(g_w2, v3(0.97, 0.5, 0), R(0.05), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_sphere: partly outside the grid", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_sphere(g_w3, v3(0.2, 0.2, 0.37), R(0.04), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_box: more sites than the remaining capacity",
            MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_fill_box(g_w2, v3(0.1, 0.1, 0), v3(0.9, 0.9, 0), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_sphere: more sites than the remaining capacity",
            MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_fill_sphere(g_w3, c3, R(0.14), 0, z, OUT(MpmIdRange)));

    /* A disk is 2D only, a sphere 3D only. */
    REFUSED("fill_sphere in 2D", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_sphere(g_w2, c, R(0.03), 0, z, OUT(MpmIdRange)));
    REFUSED("fill_disk in 3D", MPM_STATUS_INVALID_REGION,
            mpm_world_fill_disk(g_w3, c3, R(0.03), 0, z, OUT(MpmIdRange)));
}

static void step_misuse(void) {
    const double bad[] = {0.0, -0.0, -1.0, NAN, INFINITY, -INFINITY, 1e9};
    const char *label[] = {"0", "-0", "-1", "NaN", "+inf", "-inf",
                           "1e9 (more than the most substeps)"};
    unsigned k;
    MpmStatus want;
    for (k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        char name[96];
        snprintf(name, sizeof name, "step: dt %s (2D)", label[k]);
        /* A finite positive dt is refused only for the substeps it needs. */
        want = bad[k] > 0 && bad[k] < INFINITY ? MPM_STATUS_SUBSTEP_LIMIT
                                               : MPM_STATUS_INVALID_TIME_STEP;
        REFUSED(name, want, mpm_world_step(g_w2, R(bad[k]), OUT(MpmStepReport)));
        snprintf(name, sizeof name, "step: dt %s (3D)", label[k]);
        REFUSED(name, want, mpm_world_step(g_w3, R(bad[k]), OUT(MpmStepReport)));
    }
}

/* Copy-out into buffers one value short, and of no values. */
static void copy_misuse(void) {
    size_t n2 = particle_count(g_w2), n3 = particle_count(g_w3);
    size_t *written = OUT_AT(size_t, WRITTEN_AT);

#define SHORT_COPY(fn, T, w, need, label) \
    REFUSED(#fn ": one value short (" label ")", MPM_STATUS_OUTPUT_TOO_SMALL, \
            fn((w), OUT(T), (need)-1, written)); \
    REFUSED(#fn ": out_len 0 (" label ")", MPM_STATUS_OUTPUT_TOO_SMALL, fn((w), OUT(T), 0, written))

    if ((6 * n3 + 6 * n2) * sizeof(mpm_real) > WRITTEN_AT) {
        fail("copy: setup", "the sentinel area is too small for the worlds");
    }
    SHORT_COPY(mpm_world_copy_positions, mpm_real, g_w2, 2 * n2, "2D");
    SHORT_COPY(mpm_world_copy_velocities, mpm_real, g_w2, 2 * n2, "2D");
    SHORT_COPY(mpm_world_copy_stress, mpm_real, g_w2, 4 * n2, "2D");
    SHORT_COPY(mpm_world_copy_jacobians, mpm_real, g_w2, n2, "2D");
    SHORT_COPY(mpm_world_copy_status, uint32_t, g_w2, n2, "2D");
    SHORT_COPY(mpm_world_copy_positions, mpm_real, g_w3, 3 * n3, "3D");
    SHORT_COPY(mpm_world_copy_velocities, mpm_real, g_w3, 3 * n3, "3D");
    SHORT_COPY(mpm_world_copy_stress, mpm_real, g_w3, 6 * n3, "3D");
    SHORT_COPY(mpm_world_copy_jacobians, mpm_real, g_w3, n3, "3D");
    SHORT_COPY(mpm_world_copy_status, uint32_t, g_w3, n3, "3D");
#undef SHORT_COPY

    /* Controls: the exact length is accepted and reported. */
#define EXACT_COPY(fn, T, w, need, label) \
    out_reset(); \
    ACCEPTED(#fn ": exact length (" label ")", 0, fn((w), OUT(T), (need), written)); \
    expect_true(#fn ": written_out is the exact length (" label ")", *written == (need))
    EXACT_COPY(mpm_world_copy_positions, mpm_real, g_w2, 2 * n2, "2D");
    EXACT_COPY(mpm_world_copy_stress, mpm_real, g_w2, 4 * n2, "2D");
    EXACT_COPY(mpm_world_copy_positions, mpm_real, g_w3, 3 * n3, "3D");
    EXACT_COPY(mpm_world_copy_stress, mpm_real, g_w3, 6 * n3, "3D");
#undef EXACT_COPY
}

/* The effects' calls: effects not declared, particles that do not exist (refused before any
 * array is read), values not finite or out of range, faces out of range, the traction
 * capacity; then accepted controls that show the values arrive. */
static void effects_misuse(void) {
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    const char *label[3] = {"NaN", "+inf", "-inf"};
    static const uint32_t bad_face[] = {6u, 7u, 0x80000000u, 0xFFFFFFFFu};
    const size_t n2 = particle_count(g_we2), n3 = particle_count(g_we3);
    mpm_real f[3][BATCH_MAX], g[BATCH_MAX], p[BATCH_MAX];
    MpmVec3 down = v3(0, -64.0, 0);
    MpmIdRange ids;
    MpmParticlesView view;
    size_t count = 0, i;
    double alpha = -1;
    unsigned k;
    int j, a;

    if (n2 < 4 || n2 > BATCH_MAX || n3 < 4 || n3 > BATCH_MAX) {
        fail("effects: setup", "unexpected particle counts");
    }
    for (i = 0; i < BATCH_MAX; i++) {
        f[0][i] = R(0.25 * (double)(i % 4));
        f[1][i] = R(-0.5);
        f[2][i] = R(0.125);
        g[i] = R(0.5);
        p[i] = R(0.25 * (double)(i % 2));
    }

    /* Effects the world does not declare: the declaration is checked before the ids. */
    REFUSED("effects: set_particle_forces without particle forces (2D)",
            MPM_STATUS_EFFECT_NOT_DECLARED, mpm_world_set_particle_forces(g_w2, 0, f[0], f[1], NULL, 1));
    REFUSED("effects: set_particle_forces without particle forces (3D)",
            MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_forces(g_w3, 0, f[0], f[1], f[2], 1));
    REFUSED("effects: set_particle_forces without particle forces, unknown ids",
            MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_forces(g_w2, 0xFFFFFFFFu, f[0], f[1], NULL, (size_t)-1));
    REFUSED("effects: set_particle_damping without damping", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_damping(g_w2, 0, g, p, 1));
    REFUSED("effects: set_particle_damping with damping but no per-particle columns",
            MPM_STATUS_EFFECT_NOT_DECLARED, mpm_world_set_particle_damping(g_we3, 0, g, p, 1));
    REFUSED("effects: add_tractions without tractions (2D)", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_tractions(g_w2, 0, 1, MPM_FACE_Y_MAX, down, OUT(MpmIdRange)));
    REFUSED("effects: add_tractions without tractions (3D)", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_tractions(g_w3, 0, 1, MPM_FACE_Z_MAX, down, OUT(MpmIdRange)));
    REFUSED("effects: set_traction_schedule without tractions", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_traction_schedule(g_w2, 0, 1, 1));
    REFUSED("effects: add_surface_tractions without tractions", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_surface_tractions(g_w2, 0, 1, v3(0, 1, 0), R(0.1), down,
                                            OUT(MpmIdRange)));
    REFUSED("effects: add_follower_tractions without tractions", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_follower_tractions(g_w2, 0, 1, v3(0, 1, 0), R(0.1), down,
                                             OUT(MpmIdRange)));
    REFUSED("effects: add_tractions without tractions, unknown ids",
            MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_tractions(g_w2, 0xFFFFFFFFu, 0xFFFFFFFFu, MPM_FACE_Y_MAX, down,
                                    OUT(MpmIdRange)));
    REFUSED("effects: clear_tractions without tractions (2D)", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_clear_tractions(g_w2));
    REFUSED("effects: clear_tractions without tractions (3D)", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_clear_tractions(g_w3));
    REFUSED("effects: remove_tractions without tractions", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_remove_tractions(g_w2, 0, 0));
    ACCEPTED("effects: traction_count without tractions", 0,
             mpm_world_traction_count(g_w2, &count));
    expect_true("effects: traction_count without tractions is 0", count == 0);
    ACCEPTED("effects: feedback_alpha without damping", 0, mpm_world_feedback_alpha(g_w2, &alpha));
    expect_true("effects: feedback_alpha without damping is 0", alpha == 0.0);
    alpha = -1;
    ACCEPTED("effects: feedback_alpha without a thermostat", 0,
             mpm_world_feedback_alpha(g_we3, &alpha));
    expect_true("effects: feedback_alpha without a thermostat is 0", alpha == 0.0);

    /* Particles that do not exist. */
#define UNKNOWN(label_, first, n) \
    REFUSED("effects: set_particle_forces " label_, MPM_STATUS_UNKNOWN_PARTICLE, \
            mpm_world_set_particle_forces(g_we2, (first), f[0], f[1], NULL, (n))); \
    REFUSED("effects: set_particle_damping " label_, MPM_STATUS_UNKNOWN_PARTICLE, \
            mpm_world_set_particle_damping(g_we2, (first), g, p, (n)))
    UNKNOWN("first = count, 1 particle", (uint32_t)n2, 1);
    UNKNOWN("first = count - 1, 2 particles", (uint32_t)n2 - 1, 2);
    UNKNOWN("first 0, count + 1 particles", 0, n2 + 1);
    UNKNOWN("first = count + 1, 0 particles", (uint32_t)n2 + 1, 0);
    UNKNOWN("first 0xFFFFFFFF, 1 particle", 0xFFFFFFFFu, 1);
    UNKNOWN("first 1, SIZE_MAX particles", 1, (size_t)-1);
    UNKNOWN("first 0xFFFFFFFF, SIZE_MAX particles", 0xFFFFFFFFu, (size_t)-1);
#undef UNKNOWN
    REFUSED("effects: set_particle_forces first = count, 1 particle (3D)",
            MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_set_particle_forces(g_we3, (uint32_t)n3, f[0], f[1], f[2], 1));
#define UNKNOWN_TRACTION(label_, first, n) \
    REFUSED("effects: add_tractions " label_, MPM_STATUS_UNKNOWN_PARTICLE, \
            mpm_world_add_tractions(g_we2, (first), (n), MPM_FACE_Y_MAX, down, OUT(MpmIdRange)))
    UNKNOWN_TRACTION("first = count, 1 particle", (uint32_t)n2, 1);
    UNKNOWN_TRACTION("first = count - 1, 2 particles", (uint32_t)n2 - 1, 2);
    UNKNOWN_TRACTION("first 0, count + 1 particles", 0, (uint32_t)n2 + 1);
    UNKNOWN_TRACTION("first = count + 1, 0 particles", (uint32_t)n2 + 1, 0);
    UNKNOWN_TRACTION("first 0xFFFFFFFF, 2 particles (past 32 bits)", 0xFFFFFFFFu, 2);
    UNKNOWN_TRACTION("first 1, 0xFFFFFFFF particles (past 32 bits)", 1, 0xFFFFFFFFu);
#undef UNKNOWN_TRACTION
    REFUSED("effects: add_tractions first = count, 1 particle (3D)", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_add_tractions(g_we3, (uint32_t)n3, 1, MPM_FACE_Z_MAX, down,
                                    OUT(MpmIdRange)));

    /* A count past the particles is refused before any array is read: 1-value arrays, and
     * below arrays in a page that cannot be read at all. */
    {
        mpm_real *one[3];
        for (k = 0; k < 3; k++) {
            one[k] = (mpm_real *)malloc(sizeof(mpm_real));
            if (one[k] == NULL) {
                fail("effects: setup", "out of memory");
            }
            *one[k] = R(0.25);
        }
        REFUSED("effects: set_particle_forces count + 1 with 1-value arrays",
                MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_set_particle_forces(g_we2, 0, one[0], one[1], one[2], n2 + 1));
        REFUSED("effects: set_particle_damping count + 1 with 1-value arrays",
                MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_set_particle_damping(g_we2, 0, one[0], one[1], n2 + 1));
        for (k = 0; k < 3; k++) {
            free(one[k]);
        }
    }
#ifdef MISUSE_HAVE_MMAN
    {
        long page = sysconf(_SC_PAGESIZE);
        void *q = mmap(NULL, (size_t)page, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        const mpm_real *none = (const mpm_real *)q;
        if (q == MAP_FAILED) {
            fail("effects: setup", "mmap failed");
        }
        REFUSED("effects: set_particle_forces count + 1 with arrays in a no-access page",
                MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_set_particle_forces(g_we2, 0, none, none, none, n2 + 1));
        REFUSED("effects: set_particle_forces count SIZE_MAX with arrays in a no-access page",
                MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_set_particle_forces(g_we3, 0, none, none, none, (size_t)-1));
        REFUSED("effects: set_particle_damping count + 1 with arrays in a no-access page",
                MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_set_particle_damping(g_we2, 0, none, none, n2 + 1));
        REFUSED("effects: set_particle_damping count SIZE_MAX with arrays in a no-access page",
                MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_set_particle_damping(g_we2, 1, none, none, (size_t)-1));
        munmap(q, (size_t)page);
    }
#endif

    /* Values not finite or out of range, in the last of three particles: none is set. */
    for (j = 0; j < 3; j++) {
        char name[96];
        for (a = 0; a < 3; a++) {
            const mpm_real keep = f[a][2];
            f[a][2] = R(bad[j]);
            if (a < 2) {
                snprintf(name, sizeof name, "effects: set_particle_forces f%c %s (2D)", 'x' + a,
                         label[j]);
                REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                        mpm_world_set_particle_forces(g_we2, 0, f[0], f[1], NULL, 3));
            }
            snprintf(name, sizeof name, "effects: set_particle_forces f%c %s (3D)", 'x' + a,
                     label[j]);
            REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                    mpm_world_set_particle_forces(g_we3, 0, f[0], f[1], f[2], 3));
            f[a][2] = keep;
        }
        g[2] = R(bad[j]);
        snprintf(name, sizeof name, "effects: set_particle_damping alpha_g %s", label[j]);
        REFUSED(name, MPM_STATUS_INVALID_EFFECT, mpm_world_set_particle_damping(g_we2, 0, g, p, 3));
        g[2] = R(0.5);
        p[2] = R(bad[j]);
        snprintf(name, sizeof name, "effects: set_particle_damping alpha_p %s", label[j]);
        REFUSED(name, MPM_STATUS_INVALID_EFFECT, mpm_world_set_particle_damping(g_we2, 0, g, p, 3));
        p[2] = R(0.0);
        for (a = 0; a < 2; a++) {
            MpmVec3 t = down;
            if (a == 0) {
                t.x = R(bad[j]);
            } else {
                t.y = R(bad[j]);
            }
            snprintf(name, sizeof name, "effects: add_tractions traction.%c %s", 'x' + a,
                     label[j]);
            REFUSED(name, MPM_STATUS_INVALID_EFFECT,
                    mpm_world_add_tractions(g_we2, 0, 2, MPM_FACE_Y_MAX, t, OUT(MpmIdRange)));
        }
        {
            MpmVec3 t = down;
            t.z = R(bad[j]);
            snprintf(name, sizeof name, "effects: add_tractions traction.z %s (3D)", label[j]);
            REFUSED(name, MPM_STATUS_INVALID_EFFECT,
                    mpm_world_add_tractions(g_we3, 0, 2, MPM_FACE_Z_MAX, t, OUT(MpmIdRange)));
        }
    }
    g[1] = R(-1.0);
    REFUSED("effects: set_particle_damping alpha_g -1", MPM_STATUS_INVALID_EFFECT,
            mpm_world_set_particle_damping(g_we2, 0, g, p, 3));
    g[1] = R(0.5);
    p[0] = R(-1e-30);
    REFUSED("effects: set_particle_damping alpha_p -1e-30", MPM_STATUS_INVALID_EFFECT,
            mpm_world_set_particle_damping(g_we2, 0, g, p, 3));
    p[0] = R(0.0);

    /* Faces: out of the enum, or a z face in 2D. */
    for (k = 0; k < sizeof bad_face / sizeof bad_face[0]; k++) {
        char name[96];
        snprintf(name, sizeof name, "effects: add_tractions face %u", (unsigned)bad_face[k]);
        REFUSED(name, MPM_STATUS_INVALID_ENUM,
                mpm_world_add_tractions(g_we2, 0, 1, bad_face[k], down, OUT(MpmIdRange)));
        snprintf(name, sizeof name, "effects: add_tractions face %u (3D)", (unsigned)bad_face[k]);
        REFUSED(name, MPM_STATUS_INVALID_ENUM,
                mpm_world_add_tractions(g_we3, 0, 1, bad_face[k], down, OUT(MpmIdRange)));
    }
    REFUSED("effects: add_tractions face Z_MIN in 2D", MPM_STATUS_INVALID_EFFECT,
            mpm_world_add_tractions(g_we2, 0, 1, MPM_FACE_Z_MIN, down, OUT(MpmIdRange)));
    REFUSED("effects: add_tractions face Z_MAX in 2D", MPM_STATUS_INVALID_EFFECT,
            mpm_world_add_tractions(g_we2, 0, 1, MPM_FACE_Z_MAX, down, OUT(MpmIdRange)));

    /* A surface traction's normal must have a length and its area be positive, all finite;
     * the particle range is checked as add_tractions' is. */
    {
        const struct {
            const char *what;
            MpmVec3 normal;
            mpm_real area;
            MpmVec3 traction;
        } bad[] = {
            {"zero normal", {0, 0, 0}, R(0.1), {0, -1, 0}},
            {"normal only along z in 2D", {0, 0, 1}, R(0.1), {0, -1, 0}},
            {"NaN normal", {R(NAN), 1, 0}, R(0.1), {0, -1, 0}},
            {"infinite normal", {R(INFINITY), 0, 0}, R(0.1), {0, -1, 0}},
            {"area 0", {1, 0, 0}, 0, {0, -1, 0}},
            {"area -1", {1, 0, 0}, R(-1.0), {0, -1, 0}},
            {"area NaN", {1, 0, 0}, R(NAN), {0, -1, 0}},
            {"area infinite", {1, 0, 0}, R(INFINITY), {0, -1, 0}},
            {"traction NaN", {1, 0, 0}, R(0.1), {R(NAN), 0, 0}},
        };
        char name[96];
        for (k = 0; k < sizeof bad / sizeof bad[0]; k++) {
            snprintf(name, sizeof name, "effects: add_surface_tractions %s", bad[k].what);
            REFUSED(name, MPM_STATUS_INVALID_EFFECT,
                    mpm_world_add_surface_tractions(g_we2, 0, 1, bad[k].normal, bad[k].area,
                                                    bad[k].traction, OUT(MpmIdRange)));
        }
        REFUSED("effects: add_surface_tractions first = count", MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_add_surface_tractions(g_we2, (uint32_t)n2, 1, v3(1, 0, 0), R(0.1),
                                                down, OUT(MpmIdRange)));
    }

    /* The traction capacity (8 in 2D, 4 in 3D); a z component in 2D is not read. */
    {
        MpmVec3 t = down;
        t.z = R(NAN);
        ACCEPTED("effects: add_tractions 1 with traction.z NaN in 2D", 1,
                 mpm_world_add_tractions(g_we2, 0, 1, MPM_FACE_X_MIN, t, &ids));
        expect_true("effects: first traction id 0", ids.first == 0 && ids.count == 1);
    }
    ACCEPTED("effects: add_tractions 4 more", 1,
             mpm_world_add_tractions(g_we2, 0, 4, MPM_FACE_Y_MAX, down, &ids));
    expect_true("effects: traction ids 1..5", ids.first == 1 && ids.count == 4);
    REFUSED("effects: add_tractions 4 into 3 left", MPM_STATUS_TRACTION_CAPACITY_EXCEEDED,
            mpm_world_add_tractions(g_we2, 0, 4, MPM_FACE_Y_MAX, down, OUT(MpmIdRange)));
    ACCEPTED("effects: add_tractions the 3 left", 1,
             mpm_world_add_tractions(g_we2, 1, 3, MPM_FACE_X_MAX, down, &ids));
    expect_true("effects: traction ids 5..8", ids.first == 5 && ids.count == 3);
    REFUSED("effects: add_tractions 1 into a full table", MPM_STATUS_TRACTION_CAPACITY_EXCEEDED,
            mpm_world_add_tractions(g_we2, 0, 1, MPM_FACE_Y_MAX, down, OUT(MpmIdRange)));
    REFUSED("effects: add_tractions every particle into a full table",
            MPM_STATUS_TRACTION_CAPACITY_EXCEEDED,
            mpm_world_add_tractions(g_we2, 0, (uint32_t)n2, MPM_FACE_Y_MAX, down,
                                    OUT(MpmIdRange)));
    ids.first = ids.count = 12345;
    ACCEPTED("effects: add_tractions 0 into a full table", 0,
             mpm_world_add_tractions(g_we2, 0, 0, MPM_FACE_Y_MAX, down, &ids));
    expect_true("effects: 0 tractions give an empty range", ids.count == 0);
    ACCEPTED("effects: traction_count", 0, mpm_world_traction_count(g_we2, &count));
    expect_true("effects: traction_count is the capacity", count == 8);
    /* A schedule for part of the table; a schedule past the list or a range past the table
     * is refused and changes nothing; an empty range at its end changes nothing. */
    ACCEPTED("effects: set_traction_schedule 2..5 to the last", 1,
             mpm_world_set_traction_schedule(g_we2, 2, 3, MPM_TRACTION_SCHEDULES - 1));
    REFUSED("effects: set_traction_schedule past the list", MPM_STATUS_INVALID_EFFECT,
            mpm_world_set_traction_schedule(g_we2, 0, 1, MPM_TRACTION_SCHEDULES));
    REFUSED("effects: set_traction_schedule 0xFFFFFFFF", MPM_STATUS_INVALID_EFFECT,
            mpm_world_set_traction_schedule(g_we2, 0, 1, 0xFFFFFFFFu));
    REFUSED("effects: set_traction_schedule 7..9 of 8", MPM_STATUS_UNKNOWN_TRACTION,
            mpm_world_set_traction_schedule(g_we2, 7, 2, 0));
    REFUSED("effects: set_traction_schedule from 0xFFFFFFFF", MPM_STATUS_UNKNOWN_TRACTION,
            mpm_world_set_traction_schedule(g_we2, 0xFFFFFFFFu, 2, 0));
    ACCEPTED("effects: set_traction_schedule of none at the end", 0,
             mpm_world_set_traction_schedule(g_we2, 8, 0, 1));
    REFUSED("effects: add_tractions 5 into 4 (3D)", MPM_STATUS_TRACTION_CAPACITY_EXCEEDED,
            mpm_world_add_tractions(g_we3, 0, 5, MPM_FACE_Z_MAX, down, OUT(MpmIdRange)));
    ACCEPTED("effects: add_tractions 4 (3D)", 1,
             mpm_world_add_tractions(g_we3, 0, 4, MPM_FACE_Z_MAX, down, &ids));
    REFUSED("effects: add_tractions 1 into a full table (3D)",
            MPM_STATUS_TRACTION_CAPACITY_EXCEEDED,
            mpm_world_add_tractions(g_we3, 0, 1, MPM_FACE_Z_MIN, down, OUT(MpmIdRange)));
    ACCEPTED("effects: step with a full traction table (2D)", 1,
             mpm_world_step(g_we2, R(1.0 / 256.0), OUT(MpmStepReport)));
    ACCEPTED("effects: step with a full traction table (3D)", 1,
             mpm_world_step(g_we3, R(1.0 / 256.0), OUT(MpmStepReport)));
    REFUSED("effects: remove_tractions past the table", MPM_STATUS_UNKNOWN_TRACTION,
            mpm_world_remove_tractions(g_we2, 6, 3));
    REFUSED("effects: remove_tractions from past the table", MPM_STATUS_UNKNOWN_TRACTION,
            mpm_world_remove_tractions(g_we2, 9, 0));
    REFUSED("effects: remove_tractions, a range past u32", MPM_STATUS_UNKNOWN_TRACTION,
            mpm_world_remove_tractions(g_we2, 0xFFFFFFFFu, 0xFFFFFFFFu));
    ACCEPTED("effects: remove_tractions 0 at the end", 0,
             mpm_world_remove_tractions(g_we2, 8, 0));
    ACCEPTED("effects: remove_tractions 2..5", 1, mpm_world_remove_tractions(g_we2, 2, 3));
    ACCEPTED("effects: traction_count after remove", 0, mpm_world_traction_count(g_we2, &count));
    expect_true("effects: traction_count after removing 3 of 8 is 5", count == 5);
    ACCEPTED("effects: clear_tractions", 1, mpm_world_clear_tractions(g_we2));
    ACCEPTED("effects: traction_count after clear", 0, mpm_world_traction_count(g_we2, &count));
    expect_true("effects: traction_count after clear is 0", count == 0);
    ACCEPTED("effects: clear_tractions of an empty table", 0, mpm_world_clear_tractions(g_we2));
    ACCEPTED("effects: add_tractions after clear", 1,
             mpm_world_add_tractions(g_we2, 0, 8, MPM_FACE_Y_MAX, down, &ids));
    expect_true("effects: traction ids after clear start at 0", ids.first == 0 && ids.count == 8);

    /* Controls: values set are the view's, the same values again change nothing, the view's
     * pointers follow the declarations. */
    ACCEPTED("effects: set_particle_forces on every particle (fz NULL in 2D)", 1,
             mpm_world_set_particle_forces(g_we2, 0, f[0], f[1], NULL, n2));
    ACCEPTED("effects: set_particle_forces with the same values", 0,
             mpm_world_set_particle_forces(g_we2, 0, f[0], f[1], f[2], n2));
    ACCEPTED("effects: set_particle_forces of 0 particles after the last", 0,
             mpm_world_set_particle_forces(g_we2, (uint32_t)n2, f[0], f[1], NULL, 0));
    ACCEPTED("effects: set_particle_forces on every particle (3D)", 1,
             mpm_world_set_particle_forces(g_we3, 0, f[0], f[1], f[2], n3));
    ACCEPTED("effects: set_particle_damping on every particle", 1,
             mpm_world_set_particle_damping(g_we2, 0, g, p, n2));
    ACCEPTED("effects: view (2D)", 0, mpm_world_particles(g_we2, &view));
    {
        int same = view.count == n2;
        for (i = 0; same && i < n2; i++) {
            same = view.force[0][i] == f[0][i] && view.force[1][i] == f[1][i] &&
                   view.damping[0][i] == g[i] && view.damping[1][i] == p[i];
        }
        expect_true("effects: the view holds the forces and damping set", same);
    }
    expect_true("effects: view pointers of the 2D world with every effect",
                view.force[0] && view.force[1] && !view.force[2] && view.damping[0] &&
                    view.damping[1] && view.affine[0] && view.affine[1] && !view.affine[2] &&
                    view.affine[3] && view.affine[4] && !view.affine[5] && !view.affine[6] &&
                    !view.affine[7] && !view.affine[8]);
    ACCEPTED("effects: view (3D)", 0, mpm_world_particles(g_we3, &view));
    expect_true("effects: view pointers of the 3D world (forces only)",
                view.force[0] && view.force[1] && view.force[2] && view.force[2][n3 - 1] == f[2][n3 - 1] &&
                    !view.damping[0] && !view.damping[1] && !view.affine[0] && !view.affine[4] &&
                    !view.affine[8]);
    ACCEPTED("effects: view (2D, nothing declared)", 0, mpm_world_particles(g_w2, &view));
    {
        int none = 1;
        for (k = 0; k < 9; k++) {
            none &= view.affine[k] == NULL && (k >= 3 || view.force[k] == NULL) &&
                    (k >= 2 || view.damping[k] == NULL);
        }
        expect_true("effects: view pointers of a world without effects are NULL", none);
    }
    ACCEPTED("effects: step (2D)", 1, mpm_world_step(g_we2, R(1.0 / 256.0), OUT(MpmStepReport)));
    alpha = -1;
    ACCEPTED("effects: feedback_alpha", 0, mpm_world_feedback_alpha(g_we2, &alpha));
    expect_true("effects: feedback_alpha in [0, max_alpha]", alpha >= 0.0 && alpha <= 8.0);
}

/* The transported scalars' calls: a field out of the enum, fields and sources not declared,
 * particles that do not exist (refused before any array is read), values not finite; then
 * accepted controls that show the values arrive and that the view's pointers follow the
 * declarations. g_we2 declares heat and diffusion with sources, g_we3 heat without sources. */
typedef MpmStatus (*SetScalar)(MpmWorld *, MpmScalarField, uint32_t, const mpm_real *, size_t);

static void transport_misuse(void) {
    static const uint32_t bad_field[] = {2u, 3u, 0x80000000u, 0xFFFFFFFFu};
    const double bad[3] = {NAN, INFINITY, -INFINITY};
    const char *label[3] = {"NaN", "+inf", "-inf"};
    const SetScalar set[2] = {mpm_world_set_particle_scalar, mpm_world_set_particle_sources};
    const char *set_name[2] = {"set_particle_scalar", "set_particle_sources"};
    const MpmScalarField field[2] = {MPM_SCALAR_FIELD_TEMPERATURE,
                                     MPM_SCALAR_FIELD_CONCENTRATION};
    const char *field_name[2] = {"temperature", "concentration"};
    const size_t n2 = particle_count(g_we2), n3 = particle_count(g_we3);
    mpm_real v[BATCH_MAX], t[BATCH_MAX], c[BATCH_MAX], q[BATCH_MAX];
    MpmParticlesView view;
    size_t i;
    unsigned k;
    int fn, fd, j;
    char name[128];

    if (n2 < 4 || n2 > BATCH_MAX || n3 < 4 || n3 > BATCH_MAX) {
        fail("transport: setup", "unexpected particle counts");
    }
    for (i = 0; i < BATCH_MAX; i++) {
        v[i] = R(0.5);
        t[i] = R(290.0 + 0.25 * (double)i);
        c[i] = R(0.125 * (double)(i % 8));
        q[i] = R(1e9); /* W/m^3: 1000 K/s in the default material (rho C_p = 1e6) */
    }

    /* The field's number is checked before the declaration. */
    for (fn = 0; fn < 2; fn++) {
        for (k = 0; k < sizeof bad_field / sizeof bad_field[0]; k++) {
            snprintf(name, sizeof name, "transport: %s field %u", set_name[fn],
                     (unsigned)bad_field[k]);
            REFUSED(name, MPM_STATUS_INVALID_ENUM,
                    set[fn](g_we2, (MpmScalarField)bad_field[k], 0, v, 1));
            snprintf(name, sizeof name, "transport: %s field %u on a world without transport",
                     set_name[fn], (unsigned)bad_field[k]);
            REFUSED(name, MPM_STATUS_INVALID_ENUM,
                    set[fn](g_w2, (MpmScalarField)bad_field[k], 0, v, 1));
        }
    }

    /* Fields and sources not declared: the declaration is checked before the ids. */
    for (fn = 0; fn < 2; fn++) {
        for (fd = 0; fd < 2; fd++) {
            snprintf(name, sizeof name, "transport: %s %s without transport (2D)", set_name[fn],
                     field_name[fd]);
            REFUSED(name, MPM_STATUS_EFFECT_NOT_DECLARED, set[fn](g_w2, field[fd], 0, v, 1));
            snprintf(name, sizeof name, "transport: %s %s without transport (3D)", set_name[fn],
                     field_name[fd]);
            REFUSED(name, MPM_STATUS_EFFECT_NOT_DECLARED, set[fn](g_w3, field[fd], 0, v, 1));
            snprintf(name, sizeof name, "transport: %s %s without transport, unknown ids",
                     set_name[fn], field_name[fd]);
            REFUSED(name, MPM_STATUS_EFFECT_NOT_DECLARED,
                    set[fn](g_w2, field[fd], 0xFFFFFFFFu, v, (size_t)-1));
        }
    }
    REFUSED("transport: set_particle_scalar concentration with heat only (3D)",
            MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_scalar(g_we3, MPM_SCALAR_FIELD_CONCENTRATION, 0, v, 1));
    REFUSED("transport: set_particle_sources temperature with heat but no sources (3D)",
            MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_sources(g_we3, MPM_SCALAR_FIELD_TEMPERATURE, 0, v, 1));
    REFUSED("transport: set_particle_sources temperature without sources, unknown ids",
            MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_sources(g_we3, MPM_SCALAR_FIELD_TEMPERATURE, 0xFFFFFFFFu, v,
                                           (size_t)-1));
    REFUSED("transport: set_particle_sources concentration with heat only (3D)",
            MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_sources(g_we3, MPM_SCALAR_FIELD_CONCENTRATION, 0, v, 1));

    /* Particles that do not exist. */
    for (fn = 0; fn < 2; fn++) {
        for (fd = 0; fd < 2; fd++) {
#define UNKNOWN(label_, first, n) \
    snprintf(name, sizeof name, "transport: %s %s %s", set_name[fn], field_name[fd], label_); \
    REFUSED(name, MPM_STATUS_UNKNOWN_PARTICLE, set[fn](g_we2, field[fd], (first), v, (n)))
            UNKNOWN("first = count, 1 particle", (uint32_t)n2, 1);
            UNKNOWN("first = count - 1, 2 particles", (uint32_t)n2 - 1, 2);
            UNKNOWN("first 0, count + 1 particles", 0, n2 + 1);
            UNKNOWN("first = count + 1, 0 particles", (uint32_t)n2 + 1, 0);
            UNKNOWN("first 0xFFFFFFFF, 1 particle", 0xFFFFFFFFu, 1);
            UNKNOWN("first 1, SIZE_MAX particles", 1, (size_t)-1);
            UNKNOWN("first 0xFFFFFFFF, SIZE_MAX particles", 0xFFFFFFFFu, (size_t)-1);
#undef UNKNOWN
        }
    }
    REFUSED("transport: set_particle_scalar temperature first = count, 1 particle (3D)",
            MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_set_particle_scalar(g_we3, MPM_SCALAR_FIELD_TEMPERATURE, (uint32_t)n3, v,
                                          1));

    /* A count past the particles is refused before the array is read. */
    {
        mpm_real *one = (mpm_real *)malloc(sizeof(mpm_real));
        if (one == NULL) {
            fail("transport: setup", "out of memory");
        }
        *one = R(0.25);
        for (fn = 0; fn < 2; fn++) {
            for (fd = 0; fd < 2; fd++) {
                snprintf(name, sizeof name, "transport: %s %s count + 1 with a 1-value array",
                         set_name[fn], field_name[fd]);
                REFUSED(name, MPM_STATUS_UNKNOWN_PARTICLE,
                        set[fn](g_we2, field[fd], 0, one, n2 + 1));
            }
        }
        free(one);
    }
#ifdef MISUSE_HAVE_MMAN
    {
        long page = sysconf(_SC_PAGESIZE);
        void *q = mmap(NULL, (size_t)page, PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
        const mpm_real *none = (const mpm_real *)q;
        if (q == MAP_FAILED) {
            fail("transport: setup", "mmap failed");
        }
        for (fn = 0; fn < 2; fn++) {
            for (fd = 0; fd < 2; fd++) {
                snprintf(name, sizeof name,
                         "transport: %s %s count + 1 with an array in a no-access page",
                         set_name[fn], field_name[fd]);
                REFUSED(name, MPM_STATUS_UNKNOWN_PARTICLE,
                        set[fn](g_we2, field[fd], 0, none, n2 + 1));
                snprintf(name, sizeof name,
                         "transport: %s %s count SIZE_MAX with an array in a no-access page",
                         set_name[fn], field_name[fd]);
                REFUSED(name, MPM_STATUS_UNKNOWN_PARTICLE,
                        set[fn](g_we2, field[fd], 1, none, (size_t)-1));
            }
        }
        REFUSED("transport: set_particle_scalar temperature count SIZE_MAX with an array in a "
                "no-access page (3D)",
                MPM_STATUS_UNKNOWN_PARTICLE,
                mpm_world_set_particle_scalar(g_we3, MPM_SCALAR_FIELD_TEMPERATURE, 0, none,
                                              (size_t)-1));
        munmap(q, (size_t)page);
    }
#endif

    /* Values not finite, in the last of three particles: none is set. */
    for (j = 0; j < 3; j++) {
        v[2] = R(bad[j]);
        for (fn = 0; fn < 2; fn++) {
            for (fd = 0; fd < 2; fd++) {
                snprintf(name, sizeof name, "transport: %s %s %s", set_name[fn], field_name[fd],
                         label[j]);
                REFUSED(name, MPM_STATUS_NON_FINITE_INPUT, set[fn](g_we2, field[fd], 0, v, 3));
            }
        }
        snprintf(name, sizeof name, "transport: set_particle_scalar temperature %s (3D)",
                 label[j]);
        REFUSED(name, MPM_STATUS_NON_FINITE_INPUT,
                mpm_world_set_particle_scalar(g_we3, MPM_SCALAR_FIELD_TEMPERATURE, 0, v, 3));
    }
    v[2] = R(0.5);

    /* Controls: values set are the view's, the same values again change nothing, the view's
     * pointers follow the declarations. */
    ACCEPTED("transport: set_particle_scalar temperature on every particle", 1,
             mpm_world_set_particle_scalar(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, 0, t, n2));
    ACCEPTED("transport: set_particle_scalar temperature with the same values", 0,
             mpm_world_set_particle_scalar(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, 0, t, n2));
    ACCEPTED("transport: set_particle_scalar of 0 particles after the last", 0,
             mpm_world_set_particle_scalar(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, (uint32_t)n2, t,
                                           0));
    ACCEPTED("transport: set_particle_scalar concentration on every particle", 1,
             mpm_world_set_particle_scalar(g_we2, MPM_SCALAR_FIELD_CONCENTRATION, 0, c, n2));
    ACCEPTED("transport: set_particle_sources temperature on every particle", 1,
             mpm_world_set_particle_sources(g_we2, MPM_SCALAR_FIELD_TEMPERATURE, 0, q, n2));
    ACCEPTED("transport: set_particle_sources concentration of 0 particles after the last", 0,
             mpm_world_set_particle_sources(g_we2, MPM_SCALAR_FIELD_CONCENTRATION, (uint32_t)n2,
                                            v, 0));
    ACCEPTED("transport: set_particle_sources concentration on 2 particles", 1,
             mpm_world_set_particle_sources(g_we2, MPM_SCALAR_FIELD_CONCENTRATION, 1, v, 2));
    ACCEPTED("transport: set_particle_scalar temperature on every particle (3D)", 1,
             mpm_world_set_particle_scalar(g_we3, MPM_SCALAR_FIELD_TEMPERATURE, 0, t, n3));
    ACCEPTED("transport: view (2D)", 0, mpm_world_particles(g_we2, &view));
    expect_true("transport: view pointers of the 2D world with heat and diffusion",
                view.temperature && view.concentration && view.grid_temperature &&
                    view.grid_concentration);
    {
        int same = view.count == n2;
        for (i = 0; same && i < n2; i++) {
            same = view.temperature[i] == t[i] && view.concentration[i] == c[i];
        }
        expect_true("transport: the view holds the temperatures and concentrations set", same);
    }
    ACCEPTED("transport: view (3D)", 0, mpm_world_particles(g_we3, &view));
    expect_true("transport: view pointers of the 3D world (heat only)",
                view.temperature && view.grid_temperature && !view.concentration &&
                    !view.grid_concentration && view.temperature[n3 - 1] == t[n3 - 1]);
    ACCEPTED("transport: view (2D, nothing declared)", 0, mpm_world_particles(g_w2, &view));
    expect_true("transport: view pointers of a world without transport are NULL",
                !view.temperature && !view.concentration && !view.grid_temperature &&
                    !view.grid_concentration);
    ACCEPTED("transport: step (2D)", 1,
             mpm_world_step(g_we2, R(1.0 / 256.0), OUT(MpmStepReport)));
    ACCEPTED("transport: view after the step", 0, mpm_world_particles(g_we2, &view));
    {
        int finite = 1, heated = 1;
        for (i = 0; i < n2; i++) {
            finite &= isfinite(view.temperature[i]) && isfinite(view.grid_temperature[i]) &&
                      isfinite(view.concentration[i]) && isfinite(view.grid_concentration[i]);
            heated &= view.temperature[i] > t[i];
        }
        expect_true("transport: the values after a step are finite", finite);
        expect_true("transport: the heat source warmed every particle", heated);
    }
}

/* The axisymmetric world: its definition read back, seeding past the axis refused, the hoop
 * column in the view (NULL in every other world), J with the hoop factor, a step. */
static void axisymmetric_misuse(void) {
    MpmParticlesView view;
    MpmWorldDef d;
    MpmStepReport report;
    MpmWorld *others[4];
    mpm_real before[BATCH_MAX], jac[BATCH_MAX];
    size_t n = particle_count(g_wa), written = 0, i;
    Batch b;
    MpmParticleArrays a;
    int k, finite, moved, same;

    others[0] = g_w2;
    others[1] = g_w3;
    others[2] = g_we2;
    others[3] = g_we3;
    if (n == 0 || n > BATCH_MAX) {
        fail("axisymmetric: setup", "unexpected particle count");
    }

    ACCEPTED("axisymmetric: get_def", 0, mpm_world_get_def(g_wa, &d));
    expect_true("axisymmetric: the definition read back is axisymmetric with its origin",
                d.dimension == MPM_DIMENSION_AXISYMMETRIC2D && d.origin.x == R(-0.05) &&
                    d.faces[MPM_FACE_X_MIN] == MPM_BOUNDARY_SLIP);

    REFUSED("axisymmetric: fill_box reaching past the axis", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_box(g_wa, v3(-0.1, 0.6, 0), v3(0.1, 0.7, 0), 0, v3(0, 0, 0),
                               OUT(MpmIdRange)));
    REFUSED("axisymmetric: fill_disk across the axis", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_disk(g_wa, v3(0.0, 0.6, 0), R(0.05), 0, v3(0, 0, 0),
                                OUT(MpmIdRange)));
    batch_fill(&b, 3, 0.2, 0.6, 0.0);
    b.x[0][2] = R(-0.01);
    a = arrays_of(&b);
    REFUSED("axisymmetric: a particle at r = -0.01", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_add_particles(g_wa, &a, 3, OUT(MpmIdRange)));

    /* The view: the hoop column set only here, finite; the out-of-plane stress present. */
    ACCEPTED("axisymmetric: view", 0, mpm_world_particles(g_wa, &view));
    expect_true("axisymmetric: the view's dimension", view.dimension == MPM_DIMENSION_AXISYMMETRIC2D);
    expect_true("axisymmetric: the view's hoop pointer is set", view.hoop != NULL);
    expect_true("axisymmetric: 2D pointers (no z, four stress components)",
                view.position[2] == NULL && view.velocity[2] == NULL && view.stress[3] != NULL &&
                    view.stress[4] == NULL && view.stress[5] == NULL);
    finite = 1;
    moved = 0;
    for (i = 0; i < n; i++) {
        finite &= isfinite(view.hoop[i]) && view.hoop[i] > R(-1.0);
        moved |= view.hoop[i] != R(0.0);
        before[i] = view.hoop[i];
    }
    expect_true("axisymmetric: the hoop stretches are finite and above -1", finite);
    expect_true("axisymmetric: the box moving outwards has a hoop stretch", moved);
    for (k = 0; k < 4; k++) {
        char name[96];
        snprintf(name, sizeof name, "axisymmetric: view of world %d (not axisymmetric)", k);
        ACCEPTED(name, 0, mpm_world_particles(others[k], &view));
        snprintf(name, sizeof name, "axisymmetric: the hoop pointer of world %d is NULL", k);
        expect_true(name, view.hoop == NULL);
    }

    /* J = det(I + H) (1 + hoop): the copy-out includes the out-of-plane stretch. */
    ACCEPTED("axisymmetric: copy_jacobians", 0,
             mpm_world_copy_jacobians(g_wa, jac, BATCH_MAX, &written));
    ACCEPTED("axisymmetric: view again", 0, mpm_world_particles(g_wa, &view));
    same = written == n;
    for (i = 0; same && i < n; i++) {
        const double h00 = view.displacement_gradient[0][i], h01 = view.displacement_gradient[1][i];
        const double h10 = view.displacement_gradient[3][i], h11 = view.displacement_gradient[4][i];
        const double j = ((1.0 + h00) * (1.0 + h11) - h01 * h10) * (1.0 + (double)view.hoop[i]);
        same = fabs((double)jac[i] - j) <= 1e-5 * fabs(j);
    }
    expect_true("axisymmetric: J is det(I + H) times 1 + hoop", same);

    /* A step moves the hoop stretches, which stay finite. */
    ACCEPTED("axisymmetric: step", 1, mpm_world_step(g_wa, R(1.0 / 256.0), &report));
    ACCEPTED("axisymmetric: view after the step", 0, mpm_world_particles(g_wa, &view));
    finite = view.hoop != NULL;
    moved = 0;
    for (i = 0; finite && i < n; i++) {
        finite &= isfinite(view.hoop[i]) && view.hoop[i] > R(-1.0) &&
                  isfinite(view.grid_temperature[i]) && isfinite(view.grid_concentration[i]);
        moved |= view.hoop[i] != before[i];
    }
    expect_true("axisymmetric: the values after the step are finite", finite);
    expect_true("axisymmetric: the step changed the hoop stretches", moved);
}

/* A box of `def` (64 particles in 2D, 32 in 3D) of the default material, moving at `v` towards
 * the stick floor, stepped 16 times by 1/256 s in a world of its own (not tracked): every call
 * is accepted, the definition reads back with its shape, no particle is frozen, and the
 * positions, velocities, stress, J (> 0) and diagnostics are finite. The positions go to
 * `pos` (6 * BATCH_MAX values), their number to `*n_pos`. */
static void step_box(const char *label, MpmWorldDef def, MpmVec3 lo, MpmVec3 hi, MpmVec3 v,
                     size_t want, mpm_real *pos, size_t *n_pos) {
    MpmMaterialDef m = mpm_material_def_default();
    MpmMemoryRequirements req;
    MpmWorldDef back;
    MpmWorld *w = NULL;
    MpmIdRange ids;
    MpmStepReport report;
    MpmDiagnostics diag;
    Block mem;
    mpm_real vel[6 * BATCH_MAX], stress[6 * BATCH_MAX], jac[BATCH_MAX];
    size_t n_vel = 0, n_stress = 0, n_jac = 0, i;
    const size_t d = def.dimension == MPM_DIMENSION_SPACE3D ? 3 : 2;
    char name[128];
    uint32_t id = 0, frozen = 0;
    int step, finite;

    snprintf(name, sizeof name, "%s: mpm_memory_requirements", label);
    ACCEPTED(name, 0, mpm_memory_requirements(&def, &req));
    mem = block_new(req.bytes, req.align, 0);
    snprintf(name, sizeof name, "%s: init", label);
    ACCEPTED(name, 0, mpm_world_init(&def, mem.at, req.bytes, &w));
    snprintf(name, sizeof name, "%s: get_def", label);
    ACCEPTED(name, 0, mpm_world_get_def(w, &back));
    snprintf(name, sizeof name, "%s: the definition reads back with its shape", label);
    expect_true(name, back.shape == def.shape && back.dimension == def.dimension);
    snprintf(name, sizeof name, "%s: material", label);
    ACCEPTED(name, 0, mpm_world_add_material(w, &m, &id));
    snprintf(name, sizeof name, "%s: fill_box", label);
    ACCEPTED(name, 0, mpm_world_fill_box(w, lo, hi, id, v, &ids));
    snprintf(name, sizeof name, "%s: the box has %lu particles", label, (unsigned long)want);
    expect_true(name, ids.first == 0 && ids.count == want);
    for (step = 0; step < 16; step++) {
        if (mpm_world_step(w, R(1.0 / 256.0), &report) != MPM_STATUS_OK) {
            fail(label, "a step was refused");
        }
        frozen += report.frozen;
    }
    snprintf(name, sizeof name, "%s: 16 steps froze no particle", label);
    expect_true(name, frozen == 0);
    snprintf(name, sizeof name, "%s: copy_positions", label);
    ACCEPTED(name, 0, mpm_world_copy_positions(w, pos, 6 * BATCH_MAX, n_pos));
    snprintf(name, sizeof name, "%s: copy_velocities", label);
    ACCEPTED(name, 0, mpm_world_copy_velocities(w, vel, 6 * BATCH_MAX, &n_vel));
    snprintf(name, sizeof name, "%s: copy_stress", label);
    ACCEPTED(name, 0, mpm_world_copy_stress(w, stress, 6 * BATCH_MAX, &n_stress));
    snprintf(name, sizeof name, "%s: copy_jacobians", label);
    ACCEPTED(name, 0, mpm_world_copy_jacobians(w, jac, BATCH_MAX, &n_jac));
    snprintf(name, sizeof name, "%s: diagnostics", label);
    ACCEPTED(name, 0, mpm_world_diagnostics(w, &diag));
    finite = *n_pos == d * want && n_vel == d * want && n_stress == (d == 3 ? 6 : 4) * want &&
             n_jac == want;
    for (i = 0; finite && i < *n_pos; i++) {
        finite &= isfinite(pos[i]) && isfinite(vel[i]);
    }
    for (i = 0; finite && i < n_stress; i++) {
        finite &= isfinite(stress[i]);
    }
    for (i = 0; finite && i < n_jac; i++) {
        finite &= isfinite(jac[i]) && jac[i] > R(0.0);
    }
    finite &= diag.step_count == 16 && isfinite(diag.kinetic) && isfinite(diag.strain) &&
              isfinite(diag.momentum[0]) && isfinite(diag.momentum[1]) &&
              isfinite(diag.momentum[2]) && isfinite(diag.center_of_mass[1]);
    snprintf(name, sizeof name, "%s: positions, velocities, stress, J and diagnostics finite",
             label);
    expect_true(name, finite);
    free(mem.raw);
}

/* cpGIMP (shape 4): 2D and 3D worlds fill a box, which falls onto the floor and deforms, and
 * step with finite results; the same 2D box under GIMP ends elsewhere (cpGIMP's domains follow
 * the deformation, so shape 4 is not read as GIMP). Its margin is GIMP's one cell. */
static void cpgimp_world(void) {
    MpmWorldDef d2 = def_2d(), d3 = def_3d();
    mpm_real cp[6 * BATCH_MAX], gimp[6 * BATCH_MAX];
    size_t n_cp = 0, n_gimp = 0, i;
    int same = 1;
    Block mem;
    MpmMemoryRequirements req;
    MpmWorld *w = NULL;
    uint32_t id = 0;
    MpmMaterialDef m = mpm_material_def_default();

    d2.shape = MPM_SHAPE_CP_GIMP;
    d3.shape = MPM_SHAPE_CP_GIMP;
    step_box("cpGIMP 3D", d3, v3(0.1, 0.1, 0.1), v3(0.2, 0.2, 0.15), v3(0.5, -1.0, 0.25), 32,
             cp, &n_cp);
    step_box("cpGIMP 2D", d2, v3(0.4, 0.1, 0), v3(0.6, 0.3, 0), v3(0.25, -1.0, 0), 64, cp,
             &n_cp);
    d2.shape = MPM_SHAPE_GIMP;
    step_box("GIMP 2D", d2, v3(0.4, 0.1, 0), v3(0.6, 0.3, 0), v3(0.25, -1.0, 0), 64, gimp,
             &n_gimp);
    for (i = 0; same && i < n_cp && n_cp == n_gimp; i++) {
        same = cp[i] == gimp[i];
    }
    expect_true("cpGIMP 2D: the positions differ from GIMP's", n_cp == n_gimp && !same);

    /* The margin: one cell at every face, as GIMP's. */
    d2.shape = MPM_SHAPE_CP_GIMP;
    if (mpm_memory_requirements(&d2, &req) != MPM_STATUS_OK) {
        fail("cpGIMP margin", "mpm_memory_requirements refused the definition");
    }
    mem = block_new(req.bytes, req.align, 0);
    if (mpm_world_init(&d2, mem.at, req.bytes, &w) != MPM_STATUS_OK ||
        mpm_world_add_material(w, &m, &id) != MPM_STATUS_OK) {
        fail("cpGIMP margin", "the world or its material was refused");
    }
    REFUSED("cpGIMP 2D: fill_box reaching into the boundary margin",
            MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_box(w, v3(0.02, 0.4, 0), v3(0.2, 0.5, 0), id, v3(0, 0, 0),
                               OUT(MpmIdRange)));
    REFUSED("cpGIMP 2D: fill_box reaching into the upper margin",
            MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_fill_box(w, v3(0.4, 0.8, 0), v3(0.6, 0.98, 0), id, v3(0, 0, 0),
                               OUT(MpmIdRange)));
    free(mem.raw);
}

/* Filling the tables to capacity, then one more. */
static void capacity_misuse(void) {
    MpmMaterialDef m = mpm_material_def_default();
    MpmIdRange ids;
    uint32_t id = 0;
    Batch b;
    MpmParticleArrays a;
    size_t remaining;

    ACCEPTED("capacity: second material (capacity 2)", 1, mpm_world_add_material(g_w2, &m, &id));
    expect_true("capacity: second material has id 1", id == 1);
    REFUSED("capacity: third material", MPM_STATUS_MATERIAL_CAPACITY_EXCEEDED,
            mpm_world_add_material(g_w2, &m, OUT(uint32_t)));
    REFUSED("capacity: second material in 3D (capacity 1)", MPM_STATUS_MATERIAL_CAPACITY_EXCEEDED,
            mpm_world_add_material(g_w3, &m, OUT(uint32_t)));

    remaining = g_def2.particle_capacity - particle_count(g_w2);
    if (remaining == 0 || remaining > BATCH_MAX) {
        fail("capacity: setup", "unexpected remaining capacity");
    }
    batch_fill(&b, remaining + 1 <= BATCH_MAX ? remaining + 1 : BATCH_MAX, 0.15, 0.7, 0.0);
    a = arrays_of(&b);
    REFUSED("capacity: remaining + 1 valid particles", MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_add_particles(g_w2, &a, remaining + 1, OUT(MpmIdRange)));
    ACCEPTED("capacity: exactly the remaining particles", 1,
             mpm_world_add_particles(g_w2, &a, remaining, &ids));
    expect_true("capacity: ids of the last particles",
                ids.count == remaining && ids.first + ids.count == g_def2.particle_capacity);
    REFUSED("capacity: one particle into a full world", MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_add_particles(g_w2, &a, 1, OUT(MpmIdRange)));
    REFUSED("capacity: fill_box into a full world", MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_fill_box(g_w2, v3(0.4, 0.8, 0), v3(0.45, 0.85, 0), 1, v3(0, 0, 0),
                               OUT(MpmIdRange)));
    REFUSED("capacity: fill_disk into a full world", MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_fill_disk(g_w2, v3(0.5, 0.8, 0), R(0.03), 1, v3(0, 0, 0),
                                OUT(MpmIdRange)));
    ids.first = ids.count = 12345;
    ACCEPTED("capacity: 0 particles into a full world", 0,
             mpm_world_add_particles(g_w2, &a, 0, &ids));
    expect_true("capacity: 0 particles give an empty id range", ids.count == 0);
}

/* mpm_status_string: a description for every status, "unknown status" for anything else. */
static void status_strings(void) {
    static const MpmStatus known[] = {
        MPM_STATUS_OK,
        MPM_STATUS_BUFFER_TOO_SMALL,
        MPM_STATUS_BUFFER_MISALIGNED,
        MPM_STATUS_NOT_A_WORLD,
        MPM_STATUS_UNSUPPORTED,
        MPM_STATUS_INVALID_CELL_SIZE,
        MPM_STATUS_INVALID_CELL_COUNT,
        MPM_STATUS_INVALID_CAPACITY,
        MPM_STATUS_INVALID_FLIP_BETA,
        MPM_STATUS_INVALID_CFL,
        MPM_STATUS_INVALID_EXP_TERMS,
        MPM_STATUS_INVALID_PARTICLES_PER_CELL,
        MPM_STATUS_NON_FINITE_DEFINITION,
        MPM_STATUS_INVALID_MATERIAL,
        MPM_STATUS_MATERIAL_CAPACITY_EXCEEDED,
        MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
        MPM_STATUS_UNKNOWN_MATERIAL,
        MPM_STATUS_NON_FINITE_INPUT,
        MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME,
        MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
        MPM_STATUS_LENGTH_MISMATCH,
        MPM_STATUS_INVALID_TIME_STEP,
        MPM_STATUS_INVALID_REGION,
        MPM_STATUS_INVALID_EFFECT,
        MPM_STATUS_EFFECT_NOT_DECLARED,
        MPM_STATUS_UNKNOWN_PARTICLE,
        MPM_STATUS_TRACTION_CAPACITY_EXCEEDED,
        MPM_STATUS_INVALID_AXIS,
        MPM_STATUS_SUBSTEP_LIMIT,
        MPM_STATUS_INVALID_STATE,
        MPM_STATUS_INVALID_LIMIT,
        MPM_STATUS_INVALID_DEFORMATION,
        MPM_STATUS_INVALID_TRANSFER,
        MPM_STATUS_UNKNOWN_TRACTION,
        MPM_STATUS_STABLE_STEP_TOO_SHORT,
        MPM_STATUS_COLLIDER_CAPACITY_EXCEEDED,
        MPM_STATUS_UNKNOWN_COLLIDER,
        MPM_STATUS_INVALID_BOUNDARY,
        MPM_STATUS_NULL_POINTER,
        MPM_STATUS_DEF_NOT_FROM_DEFAULT,
        MPM_STATUS_INVALID_ENUM,
        MPM_STATUS_OUTPUT_TOO_SMALL,
        MPM_STATUS_INTERNAL,
        MPM_STATUS_OVERLAPPING_MEMORY,
        MPM_STATUS_TASK_CONTRACT,
    };
    const size_t n_known = sizeof known / sizeof known[0];
    size_t i, j;
    uint32_t v;
    unsigned long unknown = 0;

    for (i = 0; i < n_known; i++) {
        const char *s = mpm_status_string(known[i]);
        char name[96];
        snprintf(name, sizeof name, "status string of %u is a description",
                 (unsigned)known[i]);
        expect_true(name, s != NULL && s[0] != '\0' && strcmp(s, "unknown status") != 0);
        for (j = 0; j < i; j++) {
            if (strcmp(s, mpm_status_string(known[j])) == 0) {
                snprintf(name, sizeof name, "status strings of %u and %u are equal",
                         (unsigned)known[i], (unsigned)known[j]);
                fail(name, "two statuses share a description");
            }
        }
    }
    /* Every other value up to 1024, and the extremes. */
    for (v = 0; v <= 1024; v++) {
        int is_known = 0;
        for (i = 0; i < n_known; i++) {
            is_known |= (uint32_t)known[i] == v;
        }
        if (!is_known) {
            const char *s = mpm_status_string((MpmStatus)v);
            if (s == NULL || strcmp(s, "unknown status") != 0) {
                char name[64];
                snprintf(name, sizeof name, "status string of %u", (unsigned)v);
                fail(name, "an unknown status is not described as \"unknown status\"");
            }
            unknown++;
        }
    }
    {
        char name[96];
        snprintf(name, sizeof name,
                 "status strings of the %lu unknown values up to 1024 are \"unknown status\"",
                 unknown);
        expect_true(name, unknown == 1025 - n_known);
    }
    expect_true("status string of 0x80000000 is \"unknown status\"",
                strcmp(mpm_status_string((MpmStatus)0x80000000u), "unknown status") == 0);
    expect_true("status string of 0xFFFFFFFF is \"unknown status\"",
                strcmp(mpm_status_string((MpmStatus)0xFFFFFFFFu), "unknown status") == 0);
}

/* Initial deformation: H = F - I from 9 row-major pointers. */
static void deformation_misuse(void) {
    size_t n = particle_count(g_w3), n2 = particle_count(g_w2), i, written = 0;
    mpm_real cols[9][64], jac[64];
    const mpm_real *h[9];
    int k;
    if (n > 64 || n2 > 64) {
        fail("deformation: setup", "more particles than the test's arrays");
    }
    for (k = 0; k < 9; k++) {
        for (i = 0; i < 64; i++) {
            cols[k][i] = R(0.0);
        }
        h[k] = cols[k];
    }
    REFUSED("deformation: h NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_set_displacement_gradient(g_w3, 0, NULL, n));
    h[7] = NULL;
    REFUSED("deformation 3D: h[7] NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_set_displacement_gradient(g_w3, 0, h, n));
    h[7] = cols[7];
    REFUSED("deformation: particles past the count", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_set_displacement_gradient(g_w3, 1, h, n));
    REFUSED("deformation: count SIZE_MAX", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_set_displacement_gradient(g_w3, 0, h, (size_t)-1));
    cols[0][n - 1] = R(-2.0); /* F_xx = -1: inverted */
    REFUSED("deformation: an inverted F", MPM_STATUS_INVALID_DEFORMATION,
            mpm_world_set_displacement_gradient(g_w3, 0, h, n));
    cols[0][n - 1] = R(0.0);
    cols[5][0] = R(NAN);
    REFUSED("deformation: a NaN entry", MPM_STATUS_INVALID_DEFORMATION,
            mpm_world_set_displacement_gradient(g_w3, 0, h, n));
    cols[5][0] = R(0.0);
    cols[4][0] = R(999.0); /* J = 1000, past max_volume_ratio */
    REFUSED("deformation: J past max_volume_ratio", MPM_STATUS_INVALID_DEFORMATION,
            mpm_world_set_displacement_gradient(g_w3, 0, h, n));
    cols[4][0] = R(0.0);
    /* 2D reads only h[0], h[1], h[3], h[4]: the others may be NULL. */
    for (i = 0; i < n2; i++) {
        cols[0][i] = R(0.01);
    }
    h[2] = h[5] = h[6] = h[7] = h[8] = NULL;
    ACCEPTED("deformation 2D: a stretch, unread pointers NULL", 1,
             mpm_world_set_displacement_gradient(g_w2, 0, h, n2));
    if (mpm_world_copy_jacobians(g_w2, jac, 64, &written) != MPM_STATUS_OK || written != n2) {
        fail("deformation 2D", "mpm_world_copy_jacobians refused");
    }
    {
        int all = 1;
        for (i = 0; i < n2; i++) {
            all = all && fabs((double)jac[i] - 1.01) < 1e-5;
        }
        expect_true("deformation 2D: J = det F = 1.01 for every particle", all);
    }
}

/* Colliders: every refusal with its status and the world unchanged, then a floor under a
 * block that, stepped, reads back a finite downward force over the step's length. */
static void collider_misuse(void) {
    MpmWorldDef d = def_2d();
    MpmMemoryRequirements req;
    Block mem;
    MpmWorld *w = NULL;
    MpmMaterialDef m = mpm_material_def_default();
    MpmColliderDef floor = mpm_collider_def_default(), bad;
    MpmColliderState state;
    MpmStepReport report;
    MpmIdRange ids;
    uint32_t id = 7, removed = 0;

    d.effects.collider_capacity = 1;
    if (mpm_memory_requirements(&d, &req) != MPM_STATUS_OK) {
        fail("colliders: setup", "mpm_memory_requirements refused a collider capacity");
    }
    mem = block_new(req.bytes, req.align, 0);
    if (mpm_world_init(&d, mem.at, req.bytes, &w) != MPM_STATUS_OK) {
        fail("colliders: setup", "mpm_world_init refused a collider capacity");
    }
    track(w);
    ACCEPTED("colliders: material", 1, mpm_world_add_material(w, &m, &id));
    ACCEPTED("colliders: block", 1,
             mpm_world_fill_box(w, v3(0.3, 0.3, 0), v3(0.5, 0.4, 0), 0, v3(0, 0, 0), &ids));
    floor.position = v3(0.0, 0.3, 0.0);

    REFUSED("colliders: NULL def", MPM_STATUS_NULL_POINTER,
            mpm_world_add_collider(w, NULL, OUT(uint32_t)));
    REFUSED("colliders: NULL id_out", MPM_STATUS_NULL_POINTER,
            mpm_world_add_collider(w, &floor, NULL));
    bad = floor;
    bad.internal_cookie ^= 1u;
    REFUSED("colliders: def not from the default", MPM_STATUS_DEF_NOT_FROM_DEFAULT,
            mpm_world_add_collider(w, &bad, OUT(uint32_t)));
    bad = floor;
    bad.shape = 6;
    REFUSED("colliders: shape out of range", MPM_STATUS_INVALID_ENUM,
            mpm_world_add_collider(w, &bad, OUT(uint32_t)));
    bad = floor;
    bad.contact = 3;
    REFUSED("colliders: contact out of range", MPM_STATUS_INVALID_ENUM,
            mpm_world_add_collider(w, &bad, OUT(uint32_t)));
    bad = floor;
    bad.shape = MPM_COLLIDER_SHAPE_SPHERE;
    bad.radius = R(0.0);
    REFUSED("colliders: sphere of radius 0", MPM_STATUS_INVALID_EFFECT,
            mpm_world_add_collider(w, &bad, OUT(uint32_t)));
    bad = floor;
    bad.friction = R(-1.0);
    REFUSED("colliders: negative friction", MPM_STATUS_INVALID_EFFECT,
            mpm_world_add_collider(w, &bad, OUT(uint32_t)));
    bad = floor;
    bad.rotation[0] = bad.rotation[1] = bad.rotation[2] = bad.rotation[3] = R(0.0);
    REFUSED("colliders: zero rotation", MPM_STATUS_INVALID_EFFECT,
            mpm_world_add_collider(w, &bad, OUT(uint32_t)));
    bad = floor;
    bad.shape = MPM_COLLIDER_SHAPE_SDF;
    REFUSED("colliders: a distance field past the samples added", MPM_STATUS_INVALID_EFFECT,
            mpm_world_add_collider(w, &bad, OUT(uint32_t)));
    REFUSED("colliders: distance samples not declared", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_distance_field(w, &floor.radius, 1, OUT(uint32_t)));
    REFUSED("colliders: none declared", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_collider(g_w2, &floor, OUT(uint32_t)));
    REFUSED("colliders: get an id not added", MPM_STATUS_UNKNOWN_COLLIDER,
            mpm_world_get_collider(w, 0, OUT(MpmColliderState)));
    REFUSED("colliders: set an id not added", MPM_STATUS_UNKNOWN_COLLIDER,
            mpm_world_set_collider(w, 0, &floor));
    REFUSED("colliders: get into NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_get_collider(w, 0, NULL));
    REFUSED("colliders: remove what an id not added displaces", MPM_STATUS_UNKNOWN_COLLIDER,
            mpm_world_remove_particles_in_collider(w, 0, OUT(uint32_t)));

    ACCEPTED("colliders: add the floor", 1, mpm_world_add_collider(w, &floor, &id));
    expect_true("colliders: the first id is 0", id == 0);
    REFUSED("colliders: past the capacity", MPM_STATUS_COLLIDER_CAPACITY_EXCEEDED,
            mpm_world_add_collider(w, &floor, OUT(uint32_t)));
    floor.friction = R(0.5);
    ACCEPTED("colliders: set it", 1, mpm_world_set_collider(w, 0, &floor));
    ACCEPTED("colliders: step", 1, mpm_world_step(w, R(1.0 / 256.0), &report));
    ACCEPTED("colliders: read it back", 0, mpm_world_get_collider(w, 0, &state));
    expect_true("colliders: the step's length", state.duration == R(1.0 / 256.0));
    expect_true("colliders: the block presses down on the floor",
                state.force.y < R(0.0) && state.impulse.y < R(0.0));
    expect_true("colliders: the definition read back",
                state.def.friction == R(0.5) && state.def.position.y == R(0.3));
    /* The floor's plane at the block's base: the row of particles whose domains touch it. */
    ACCEPTED("colliders: remove what the floor displaces", 1,
             mpm_world_remove_particles_in_collider(w, 0, &removed));
    expect_true("colliders: one row of the block removed", removed > 0 && removed < ids.count);
    untrack(w);
    free(mem.raw);
}

/* Setting and removing particles: every refusal, then a removal of each kind that frees
 * room for as many new particles. */
static void particle_edit_misuse(void) {
    MpmWorldDef d = def_2d();
    MpmMemoryRequirements req;
    Block mem;
    MpmWorld *w = NULL;
    MpmMaterialDef m = mpm_material_def_default();
    MpmIdRange ids;
    uint32_t id = 7, removed = 7, n, list[3], order[64], k;
    mpm_real x[2], y[2], nan_, far[2], fast[2], before[128], after[128];
    size_t written = 0;
    int permuted = 1;
    const mpm_real *affine[9] = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    uint32_t mats[2] = {0, 0}, bad_mats[2] = {0, 9};

    d.particle_capacity = 64;
    if (mpm_memory_requirements(&d, &req) != MPM_STATUS_OK) {
        fail("particles: setup", "mpm_memory_requirements refused the definition");
    }
    mem = block_new(req.bytes, req.align, 0);
    if (mpm_world_init(&d, mem.at, req.bytes, &w) != MPM_STATUS_OK) {
        fail("particles: setup", "mpm_world_init refused the definition");
    }
    track(w);
    ACCEPTED("particles: material", 1, mpm_world_add_material(w, &m, &id));
    ACCEPTED("particles: block", 1,
             mpm_world_fill_box(w, v3(0.3, 0.3, 0), v3(0.5, 0.5, 0), 0, v3(0, 0, 0), &ids));
    n = ids.count;
    expect_true("particles: the block fills the capacity", n == 64);
    x[0] = x[1] = R(0.4);
    y[0] = y[1] = R(0.45);
    nan_ = (mpm_real)NAN;
    far[0] = far[1] = R(50.0);
    fast[0] = fast[1] = R(1.0e30);

    REFUSED("particles: positions NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_set_particle_positions(w, 0, x, NULL, NULL, 2));
    REFUSED("particles: positions past the end", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_set_particle_positions(w, n - 1, x, y, NULL, 2));
    REFUSED("particles: position outside", MPM_STATUS_POSITION_OUTSIDE_DOMAIN,
            mpm_world_set_particle_positions(w, 0, far, y, NULL, 2));
    y[1] = nan_;
    REFUSED("particles: position NaN", MPM_STATUS_NON_FINITE_INPUT,
            mpm_world_set_particle_positions(w, 0, x, y, NULL, 2));
    REFUSED("particles: velocity NaN", MPM_STATUS_NON_FINITE_INPUT,
            mpm_world_set_particle_velocities(w, 0, x, y, NULL, 2));
    y[1] = R(0.45);
    REFUSED("particles: velocity no step resolves", MPM_STATUS_STABLE_STEP_TOO_SHORT,
            mpm_world_set_particle_velocities(w, 0, fast, y, NULL, 2));
    REFUSED("particles: velocities in the world's memory", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_velocities(w, 0, (const mpm_real *)(const void *)w, y, NULL, 2));
    REFUSED("particles: materials NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_set_particle_materials(w, 0, NULL, 2));
    REFUSED("particles: material unknown", MPM_STATUS_UNKNOWN_MATERIAL,
            mpm_world_set_particle_materials(w, 0, bad_mats, 2));
    REFUSED("particles: affine NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_set_particle_affine(w, 0, NULL, 2));
    REFUSED("particles: affine without APIC", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_affine(w, 0, affine, 2));
    REFUSED("particles: remove a range past the end", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_remove_particles(w, n - 1, 2, OUT(uint32_t)));
    REFUSED("particles: remove a range past u32", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_remove_particles(w, 1, 0xFFFFFFFFu, OUT(uint32_t)));
    REFUSED("particles: remove into NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_remove_particles(w, 0, 1, NULL));
    list[0] = 1;
    list[1] = n;
    list[2] = 0;
    REFUSED("particles: remove a list with an unknown id", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_remove_particle_list(w, list, 3, OUT(uint32_t)));
    REFUSED("particles: remove a NULL list", MPM_STATUS_NULL_POINTER,
            mpm_world_remove_particle_list(w, NULL, 3, OUT(uint32_t)));
    REFUSED("particles: remove a box with a NaN corner", MPM_STATUS_NON_FINITE_INPUT,
            mpm_world_remove_particles_in_box(w, v3(NAN, 0, 0), v3(1, 1, 0), OUT(uint32_t)));
    REFUSED("particles: remove a box inside out", MPM_STATUS_INVALID_REGION,
            mpm_world_remove_particles_in_box(w, v3(1, 1, 0), v3(0, 0, 0), OUT(uint32_t)));
    REFUSED("particles: sort a NULL world", MPM_STATUS_NULL_POINTER,
            mpm_world_sort_particles(NULL, OUT(uint32_t), n));
    REFUSED("particles: sort into NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_sort_particles(w, NULL, n));
    REFUSED("particles: sort into too short an order", MPM_STATUS_OUTPUT_TOO_SMALL,
            mpm_world_sort_particles(w, OUT(uint32_t), n - 1));
    REFUSED("particles: sort into the world's memory", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_sort_particles(w, (uint32_t *)(void *)w, n));
    REFUSED("particles: the world is full", MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_fill_box(w, v3(0.6, 0.3, 0), v3(0.65, 0.35, 0), 0, v3(0, 0, 0), &ids));

    ACCEPTED("particles: move two", 1, mpm_world_set_particle_positions(w, 0, x, y, NULL, 2));
    ACCEPTED("particles: give two a velocity", 1,
             mpm_world_set_particle_velocities(w, 0, y, x, NULL, 2));
    ACCEPTED("particles: give two their material", -1,
             mpm_world_set_particle_materials(w, 0, mats, 2));
    ACCEPTED("particles: remove two by range", 1, mpm_world_remove_particles(w, 4, 2, &removed));
    expect_true("particles: two removed by range", removed == 2);
    list[1] = 1;
    ACCEPTED("particles: remove by a list (a repeat)", 1,
             mpm_world_remove_particle_list(w, list, 3, &removed));
    expect_true("particles: two removed by list", removed == 2);
    ACCEPTED("particles: remove the moved ones by box", -1,
             mpm_world_remove_particles_in_box(w, v3(0.39, 0.44, 0), v3(0.41, 0.46, 0), &removed));
    ACCEPTED("particles: nothing inactive", 0, mpm_world_remove_inactive_particles(w, &removed));
    expect_true("particles: nothing inactive to remove", removed == 0);
    ACCEPTED("particles: the room is free again", 1,
             mpm_world_fill_box(w, v3(0.6, 0.3, 0), v3(0.65, 0.35, 0), 0, v3(0, 0, 0), &ids));
    /* The second box after the first, out of cell order: the sort moves them, each particle's
     * position with it (order[new] = old). */
    ACCEPTED("particles: positions before the sort", 0,
             mpm_world_copy_positions(w, before, 128, &written));
    ACCEPTED("particles: sort", 1, mpm_world_sort_particles(w, order, 64));
    ACCEPTED("particles: positions after the sort", 0,
             mpm_world_copy_positions(w, after, 128, &written));
    for (k = 0; k < n; k++) {
        permuted &= order[k] < n && after[2 * k] == before[2 * order[k]] &&
                    after[2 * k + 1] == before[2 * order[k] + 1];
    }
    expect_true("particles: the sort permutes the particles", written == 2 * n && permuted);
    untrack(w);
    free(mem.raw);
}

int main(void) {
    MpmMemoryRequirements req2, req3, reqe2, reqe3, reqa;
    Block mem2, mem3, meme2, meme3, mema;
    MpmWorldDef d3 = def_3d(), de2 = def_2d_effects(), de3 = def_3d_effects(), da = def_axisym();
    MpmMaterialDef m = mpm_material_def_default(), ma = mpm_material_def_default();
    uint32_t id;
    Batch b;
    MpmParticleArrays a;
    MpmIdRange ids;
    MpmStepReport report;

    out_reset();
    expect_true("abi version matches the header", mpm_abi_version() == MPM_GIMP_ABI_VERSION);

    /* The 2D world: one material, 4 particles from arrays, 16 from a box, one step. */
    g_def2 = def_2d();
    if (mpm_memory_requirements(&g_def2, &req2) != MPM_STATUS_OK ||
        mpm_memory_requirements(&d3, &req3) != MPM_STATUS_OK) {
        fail("setup", "mpm_memory_requirements refused a valid definition");
    }
    mem2 = block_new(req2.bytes, req2.align, 0);
    mem3 = block_new(req3.bytes, req3.align, 0);
    if (mpm_world_init(&g_def2, mem2.at, req2.bytes, &g_w2) != MPM_STATUS_OK ||
        mpm_world_init(&d3, mem3.at, req3.bytes, &g_w3) != MPM_STATUS_OK) {
        fail("setup", "mpm_world_init refused a valid definition");
    }
    if (mpm_world_bytes(g_w2, &g_w2_bytes) != MPM_STATUS_OK) {
        fail("setup", "mpm_world_bytes refused the 2D world");
    }
    if (mpm_memory_requirements(&de2, &reqe2) != MPM_STATUS_OK ||
        mpm_memory_requirements(&de3, &reqe3) != MPM_STATUS_OK) {
        fail("setup", "mpm_memory_requirements refused a definition with effects");
    }
    expect_true("setup: the declared effects take memory",
                reqe2.bytes > req2.bytes && reqe3.bytes > req3.bytes);
    meme2 = block_new(reqe2.bytes, reqe2.align, 0);
    meme3 = block_new(reqe3.bytes, reqe3.align, 0);
    if (mpm_world_init(&de2, meme2.at, reqe2.bytes, &g_we2) != MPM_STATUS_OK ||
        mpm_world_init(&de3, meme3.at, reqe3.bytes, &g_we3) != MPM_STATUS_OK) {
        fail("setup", "mpm_world_init refused a definition with effects");
    }
    if (mpm_memory_requirements(&da, &reqa) != MPM_STATUS_OK) {
        fail("setup", "mpm_memory_requirements refused the axisymmetric definition");
    }
    mema = block_new(reqa.bytes, reqa.align, 0);
    if (mpm_world_init(&da, mema.at, reqa.bytes, &g_wa) != MPM_STATUS_OK) {
        fail("setup", "mpm_world_init refused the axisymmetric definition");
    }
    track(g_w2);
    track(g_w3);
    track(g_we2);
    track(g_we3);
    track(g_wa);

    ACCEPTED("setup: 2D material", 1, mpm_world_add_material(g_w2, &m, &id));
    batch_fill(&b, 4, 0.3, 0.3, 0.0);
    a = arrays_of(&b);
    a.position[2] = NULL; /* not read in 2D */
    a.velocity[2] = NULL;
    ACCEPTED("setup: 2D particles from arrays (z arrays NULL)", 1,
             mpm_world_add_particles(g_w2, &a, 4, &ids));
    ACCEPTED("setup: 2D box", 1,
             mpm_world_fill_box(g_w2, v3(0.5, 0.5, 0), v3(0.6, 0.6, 0), 0, v3(0.1, 0, 0),
                                &ids));
    expect_true("setup: 2D box has 16 particles", ids.first == 4 && ids.count == 16);
    ACCEPTED("setup: 2D step", 1, mpm_world_step(g_w2, R(1.0 / 256.0), &report));

    ACCEPTED("setup: 3D material", 1, mpm_world_add_material(g_w3, &m, &id));
    ACCEPTED("setup: 3D sphere", 1,
             mpm_world_fill_sphere(g_w3, v3(0.2, 0.2, 0.2), R(0.03), 0, v3(0, 0, 0.25), &ids));
    expect_true("setup: 3D sphere has 8 particles", ids.first == 0 && ids.count == 8);
    ACCEPTED("setup: 3D step", 1, mpm_world_step(g_w3, R(1.0 / 256.0), &report));

    ACCEPTED("setup: 2D effects material", 1, mpm_world_add_material(g_we2, &m, &id));
    ACCEPTED("setup: 2D effects box", 1,
             mpm_world_fill_box(g_we2, v3(0.5, 0.5, 0), v3(0.6, 0.6, 0), 0, v3(0.1, 0, 0),
                                &ids));
    expect_true("setup: 2D effects box has 16 particles", ids.first == 0 && ids.count == 16);
    ACCEPTED("setup: 2D effects step", 1, mpm_world_step(g_we2, R(1.0 / 256.0), &report));
    ACCEPTED("setup: 3D effects material", 1, mpm_world_add_material(g_we3, &m, &id));
    ACCEPTED("setup: 3D effects sphere", 1,
             mpm_world_fill_sphere(g_we3, v3(0.2, 0.2, 0.2), R(0.03), 0, v3(0, 0, 0.25), &ids));
    expect_true("setup: 3D effects sphere has 8 particles", ids.first == 0 && ids.count == 8);
    ACCEPTED("setup: 3D effects step", 1, mpm_world_step(g_we3, R(1.0 / 256.0), &report));

    /* The axisymmetric world: a material that expands with temperature and swells with
     * concentration, a box on the axis moving outwards, temperatures and concentrations away
     * from the reference values, one step. */
    ma.thermal_expansion = R(1e-4);
    ma.reference_temperature = R(300.0);
    ma.swelling = R(0.01);
    ma.reference_concentration = R(0.25);
    ACCEPTED("setup: axisymmetric material that expands and swells", 1,
             mpm_world_add_material(g_wa, &ma, &id));
    ACCEPTED("setup: axisymmetric box on the axis", 1,
             mpm_world_fill_box(g_wa, v3(0.0, 0.3, 0), v3(0.1, 0.4, 0), 0, v3(0.25, 0, 0),
                                &ids));
    expect_true("setup: axisymmetric box has 16 particles", ids.first == 0 && ids.count == 16);
    {
        mpm_real t[16], c[16];
        size_t i;
        for (i = 0; i < 16; i++) {
            t[i] = R(320.0 + 4.0 * (double)i);
            c[i] = R(0.0625 * (double)i);
        }
        ACCEPTED("setup: axisymmetric temperatures", 1,
                 mpm_world_set_particle_scalar(g_wa, MPM_SCALAR_FIELD_TEMPERATURE, 0, t, 16));
        ACCEPTED("setup: axisymmetric concentrations", 1,
                 mpm_world_set_particle_scalar(g_wa, MPM_SCALAR_FIELD_CONCENTRATION, 0, c, 16));
    }
    ACCEPTED("setup: axisymmetric step", 1, mpm_world_step(g_wa, R(1.0 / 256.0), &report));

    null_pointers();
    not_a_world();
    init_misuse();
    open_misuse();
    material_misuse();
    particles_misuse();
    deformation_misuse();
    fill_misuse();
    step_misuse();
    effects_misuse();
    transport_misuse();
    axisymmetric_misuse();
    cpgimp_world();
    copy_misuse();
    capacity_misuse();
    collider_misuse();
    particle_edit_misuse();
    status_strings();

    /* After all of it both worlds still step. */
    ACCEPTED("end: 2D step", 1, mpm_world_step(g_w2, R(1.0 / 256.0), &report));
    ACCEPTED("end: 3D step", 1, mpm_world_step(g_w3, R(1.0 / 256.0), &report));
    ACCEPTED("end: 2D effects step", 1, mpm_world_step(g_we2, R(1.0 / 256.0), &report));
    ACCEPTED("end: 3D effects step", 1, mpm_world_step(g_we3, R(1.0 / 256.0), &report));
    ACCEPTED("end: axisymmetric step", 1, mpm_world_step(g_wa, R(1.0 / 256.0), &report));

    free(mem2.raw);
    free(mem3.raw);
    free(meme2.raw);
    free(meme3.raw);
    free(mema.raw);
    printf("all %lu misuse checks passed\n", g_checks);
    return 0;
}
