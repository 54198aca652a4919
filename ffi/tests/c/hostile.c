/*
 * Hostile inputs from C: the reliability contract of the C interface, checked with
 * reproducers of what a careless or hostile host does. A host may hand the library
 * memory it does not control (a snapshot read from a file, a pointer it confused with another),
 * and the library must then still
 *   - refuse, with a documented status, and change nothing and write nothing: every refused
 *     call leaves every tracked world's bytes (the FNV-1a 64 hash over its mpm_world_bytes
 *     extent) and every output (a sentinel area, or the caller memory around a world) as they
 *     were;
 *   - never crash and never read past what it was given;
 *   - never leave a world that it accepted in a state that later calls cannot handle (a world
 *     that steps must keep stepping, with finite diagnostics).
 *
 * What is checked, section by section:
 *   1. aliasing: an input array (mpm_world_set_particle_scalar / _sources / _forces / _damping,
 *      each array of mpm_world_add_particles) or an output (every read-only call, and the
 *      ids, report and id outputs of the mutating calls; world_out of mpm_world_init and
 *      mpm_world_open) that overlaps the world's memory, inside it or straddling either end,
 *      is MPM_STATUS_OVERLAPPING_MEMORY and changes nothing; the same calls with caller-owned
 *      copies, and arrays that only touch the world's ends, are accepted;
 *   2. a pointer that is not a world, 64 bytes before a page without access (zeroed and
 *      random bytes): every entry point answers MPM_STATUS_NOT_A_WORLD without crashing
 *      (it reads only the 8 bytes of the magic number);
 *   3. a world with the thermostat cannot be bricked: a snapshot with a NaN velocity does not
 *      open (MPM_STATUS_INVALID_STATE), a fill whose mass overflows to infinity is refused
 *      (MPM_STATUS_NON_FINITE_INPUT) in 2D and 3D, and the world keeps stepping with finite
 *      diagnostics and a finite thermostat alpha;
 *   4. seeding validates what adding validates: a mass that underflows to 0 is
 *      MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME; in 2D the z components of fill_box are ignored;
 *   5. mpm_world_open checks the state: single edits of a snapshot (mass, volume, status,
 *      material id, position, velocity, stress, displacement gradient, inverted F, effect
 *      columns) are MPM_STATUS_INVALID_STATE and leave the copy's bytes as they were; then
 *      thousands of copies with 1 to 8 random bytes changed (a deterministic generator): each
 *      either opens or is refused with NOT_A_WORLD / INVALID_STATE / BUFFER_TOO_SMALL without
 *      writing, and one that opens steps (or answers MPM_STATUS_SUBSTEP_LIMIT and changes
 *      nothing) with finite diagnostics and, after a step, finite particle state;
 *   6. classic MPM (linear shapes, USL) on a stick floor, thousands of steps: every step is
 *      accepted, the report's flags agree with its frozen and runaway counts, every active
 *      particle ends with J in [1 / max_volume_ratio, max_volume_ratio] and a finite stress,
 *      and the world the run leaves reopens from a snapshot;
 *   7. bounded calls: a steel block on the default grid stepped by 1/60 s needs ~20,000
 *      substeps and is refused with MPM_STATUS_SUBSTEP_LIMIT, changing nothing; max_substeps
 *      is exact (S - 1 refused, S accepted); a thermostat with a huge gain takes no more
 *      substeps than the same scene without it; limits out of range are
 *      MPM_STATUS_INVALID_LIMIT;
 *   8. the new statuses have descriptions.
 *
 * The library is Rust and not instrumented by AddressSanitizer: the page without access is
 * what shows that a non-world is read no further than its first 8 bytes.
 *
 * One line per check ("ok <name>: ..."); the first failure prints "FAIL <name>: <why>" and
 * exits with status 1. The last line on success is "all <n> hostile checks passed".
 * tests/c_checks.rs builds this file with strict warnings and with AddressSanitizer and
 * UndefinedBehaviorSanitizer, and runs it. Works for both precisions (mpm_real, R()).
 */
#if defined(__unix__) || defined(__APPLE__)
/* mmap and mprotect for the page without access (not in strict C99). */
#define _DEFAULT_SOURCE
#define HOSTILE_HAVE_MMAN 1
#endif

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef HOSTILE_HAVE_MMAN
#include <sys/mman.h>
#include <unistd.h>
#ifndef MAP_ANONYMOUS
#define MAP_ANONYMOUS MAP_ANON
#endif
#endif

#include "mpm_gimp.h"

#ifdef MPM_GIMP_F64
#define REAL_MAX DBL_MAX
#define REAL_MIN DBL_MIN
/* A cell size and Young's modulus for which the sub-cell volume times REAL_MIN underflows
 * to 0 while the material stays valid (wave speed ~1e4 m/s). */
#define TINY_CELL 1e-9
#define TINY_MODULUS 1e-300
#else
#define REAL_MAX FLT_MAX
#define REAL_MIN FLT_MIN
#define TINY_CELL 1e-4
#define TINY_MODULUS 1e-30
#endif

#include "check.h"

/* ---- reporting ------------------------------------------------------------------------- */

/* A check whose ok line carries `detail`. */
static void expect_detail(const char *name, int ok, const char *detail) {
    if (!ok) {
        char why[512];
        snprintf(why, sizeof why, "condition false (%s)", detail);
        fail(name, why);
    }
    g_checks++;
    printf("ok %s: %s\n", name, detail);
}

static void status_fail(const char *name, const char *what, MpmStatus got) {
    char why[256];
    snprintf(why, sizeof why, "%s: got %u (%s)", what, (unsigned)got, mpm_status_string(got));
    fail(name, why);
}

/* ---- memory --------------------------------------------------------------------------- */

/* `bytes` at `align` (a power of two) inside a block from malloc, with at least `lead` bytes
 * before and `trail` bytes after. */
typedef struct {
    unsigned char *raw;
    unsigned char *at;
    size_t raw_len;
} Block;

static Block block_new2(size_t bytes, size_t align, size_t lead, size_t trail) {
    Block b;
    size_t offset;
    b.raw_len = bytes + align + lead + trail;
    b.raw = (unsigned char *)malloc(b.raw_len);
    if (b.raw == NULL) {
        fail("malloc", "out of memory");
    }
    offset = lead + (align - (size_t)((uintptr_t)(b.raw + lead) % align)) % align;
    b.at = b.raw + offset;
    return b;
}

static Block block_new(size_t bytes, size_t align) { return block_new2(bytes, align, 0, 0); }

/* A world in memory of its own. */
typedef struct {
    Block mem;
    MpmWorld *w;
    size_t bytes;
} Host;

static Host host_new2(const char *name, const MpmWorldDef *d, size_t lead, size_t trail) {
    Host h;
    MpmMemoryRequirements req;
    MpmStatus s = mpm_memory_requirements(d, &req);
    if (s != MPM_STATUS_OK) {
        status_fail(name, "mpm_memory_requirements refused the definition", s);
    }
    h.mem = block_new2(req.bytes, req.align, lead, trail);
    memset(h.mem.raw, PATTERN, h.mem.raw_len);
    h.w = NULL;
    s = mpm_world_init(d, h.mem.at, req.bytes, &h.w);
    if (s != MPM_STATUS_OK) {
        status_fail(name, "mpm_world_init refused the definition", s);
    }
    h.bytes = world_extent(h.w);
    if (h.bytes != req.bytes) {
        fail(name, "mpm_world_bytes differs from mpm_memory_requirements");
    }
    return h;
}

static Host host_new(const char *name, const MpmWorldDef *d) { return host_new2(name, d, 0, 0); }

static void host_free(Host *h) {
    untrack(h->w);
    free(h->mem.raw);
    h->mem.raw = NULL;
    h->w = NULL;
}

/* A byte copy of a world's extent in memory of its own. */
static Block snapshot(const MpmWorld *w) {
    size_t n = world_extent(w);
    Block b = block_new(n, 64);
    memcpy(b.at, w, n);
    return b;
}

/* The address in `copy` of the byte at `p` of the world `w`. */
static unsigned char *in_copy(const Block *copy, const MpmWorld *w, const void *p) {
    return copy->at + ((const unsigned char *)p - (const unsigned char *)(const void *)w);
}

/* ---- guarded memory around one world ------------------------------------------------ */

/* The world whose caller-owned memory before and after its extent (filled with PATTERN) every
 * refused call must leave alone, if any. */
static const Host *g_guarded;

static int guards_intact(void) {
    const Host *h = g_guarded;
    size_t before, after;
    if (h == NULL) {
        return 1;
    }
    before = (size_t)(h->mem.at - h->mem.raw);
    after = h->mem.raw_len - before - h->bytes;
    return pattern_intact(h->mem.raw, before) && pattern_intact(h->mem.at + h->bytes, after);
}

static void guards_reset(void) {
    const Host *h = g_guarded;
    size_t before;
    if (h == NULL) {
        return;
    }
    before = (size_t)(h->mem.at - h->mem.raw);
    memset(h->mem.raw, PATTERN, before);
    memset(h->mem.at + h->bytes, PATTERN, h->mem.raw_len - before - h->bytes);
}

/* ---- scenes --------------------------------------------------------------------------- */

/* 2D: 20 x 20 cells of 0.05 m (GIMP: particles admitted in [0.05, 0.95]). */
static MpmWorldDef def_2d(uint32_t capacity) { return grid_2d(capacity, 2); }

/* The 2D definition with every effect declared (as misuse.c's def_2d_effects): APIC, damping
 * (a constant grid schedule, a thermostat, per-particle columns), particle forces, 8
 * tractions, a body force, heat conduction and diffusion, both with sources. */
static MpmWorldDef def_2d_effects(uint32_t capacity) {
    MpmWorldDef d = def_2d(capacity);
    declare_every_effect(&d);
    return d;
}

static size_t particle_count(const MpmWorld *w) {
    MpmDiagnostics d;
    if (mpm_world_diagnostics(w, &d) != MPM_STATUS_OK) {
        fail("particle_count", "mpm_world_diagnostics refused a world");
    }
    return d.particle_count;
}

static MpmParticlesView view_of(const MpmWorld *w) {
    MpmParticlesView v;
    if (mpm_world_particles(w, &v) != MPM_STATUS_OK) {
        fail("view_of", "mpm_world_particles refused a world");
    }
    return v;
}

static int diag_finite(const MpmDiagnostics *d) {
    return isfinite(d->time) && isfinite(d->mass) && isfinite(d->kinetic) &&
           isfinite(d->strain) && isfinite(d->potential) && isfinite(d->momentum[0]) &&
           isfinite(d->momentum[1]) && isfinite(d->momentum[2]) &&
           isfinite(d->angular_momentum[2]) && isfinite(d->center_of_mass[0]) &&
           isfinite(d->center_of_mass[1]);
}

/* Diagnostics of `w`, required to be accepted and finite. */
static void diag_check(const char *name, const MpmWorld *w) {
    MpmDiagnostics d;
    char detail[160];
    MpmStatus s = mpm_world_diagnostics(w, &d);
    if (s != MPM_STATUS_OK) {
        status_fail(name, "mpm_world_diagnostics refused", s);
    }
    snprintf(detail, sizeof detail, "t %.6g, mass %.6g, kinetic %.6g, strain %.6g", d.time,
             d.mass, d.kinetic, d.strain);
    expect_detail(name, diag_finite(&d), detail);
}

/* Every active particle of `w` has a finite position, velocity and stress and J = det F in
 * [1 / r, r] (r the definition's max_volume_ratio, with a relative slack of 1e-3 for the
 * different rounding of the copy-out's determinant). Returns 1, or 0 with the reason in
 * `why`. */
static int active_state_ok(const MpmWorld *w, char *why, size_t why_len) {
    MpmParticlesView v;
    MpmWorldDef def;
    mpm_real *jac;
    size_t n, written = 0, i;
    int a, d3, ok = 1;
    double r, lo, hi;

    if (mpm_world_particles(w, &v) != MPM_STATUS_OK || mpm_world_get_def(w, &def) != MPM_STATUS_OK) {
        snprintf(why, why_len, "the view or the definition was refused");
        return 0;
    }
    n = v.count;
    d3 = v.dimension == MPM_DIMENSION_SPACE3D;
    jac = (mpm_real *)malloc((n + 1) * sizeof(mpm_real));
    if (jac == NULL) {
        fail("active_state_ok", "out of memory");
    }
    if (mpm_world_copy_jacobians(w, jac, n, &written) != MPM_STATUS_OK || written != n) {
        snprintf(why, why_len, "copy_jacobians refused or short");
        free(jac);
        return 0;
    }
    r = (double)def.max_volume_ratio;
    lo = (1.0 / r) * (1.0 - 1e-3);
    hi = r * (1.0 + 1e-3);
    for (i = 0; ok && i < n; i++) {
        if (v.status[i] != MPM_PARTICLE_STATUS_ACTIVE) {
            continue;
        }
        for (a = 0; a < (d3 ? 3 : 2); a++) {
            if (!isfinite(v.position[a][i]) || !isfinite(v.velocity[a][i])) {
                snprintf(why, why_len, "active particle %lu: position or velocity not finite",
                         (unsigned long)i);
                ok = 0;
            }
        }
        for (a = 0; ok && a < (d3 ? 6 : 4); a++) {
            if (!isfinite(v.stress[a][i])) {
                snprintf(why, why_len, "active particle %lu: stress[%d] %g", (unsigned long)i, a,
                         (double)v.stress[a][i]);
                ok = 0;
            }
        }
        if (ok && !((double)jac[i] >= lo && (double)jac[i] <= hi)) {
            snprintf(why, why_len, "active particle %lu: J %g outside [1/%g, %g]",
                     (unsigned long)i, (double)jac[i], r, r);
            ok = 0;
        }
    }
    free(jac);
    return ok;
}

static void active_check(const char *name, const MpmWorld *w) {
    char why[256];
    if (!active_state_ok(w, why, sizeof why)) {
        fail(name, why);
    }
    g_checks++;
    printf("ok %s\n", name);
}

/* A deterministic generator (64-bit LCG, high bits). */
static uint64_t g_rng = UINT64_C(0x853c49e6748fea9b);

static uint32_t rnd(void) {
    g_rng = g_rng * UINT64_C(6364136223846793005) + UINT64_C(1442695040888963407);
    return (uint32_t)(g_rng >> 33);
}

/* ---- 8. the new statuses -------------------------------------------------------------- */

static void new_status_strings(void) {
    static const MpmStatus fresh[] = {
        MPM_STATUS_SUBSTEP_LIMIT,
        MPM_STATUS_INVALID_STATE,
        MPM_STATUS_INVALID_LIMIT,
        MPM_STATUS_OVERLAPPING_MEMORY,
    };
    static const unsigned number[] = {28, 29, 30, 69};
    static const MpmStatus older[] = {
        MPM_STATUS_NOT_A_WORLD,          MPM_STATUS_NON_FINITE_INPUT,
        MPM_STATUS_INVALID_TIME_STEP,    MPM_STATUS_INVALID_AXIS,
        MPM_STATUS_NULL_POINTER,         MPM_STATUS_OUTPUT_TOO_SMALL,
        MPM_STATUS_INTERNAL,
    };
    size_t i, j;
    char name[128];
    for (i = 0; i < sizeof fresh / sizeof fresh[0]; i++) {
        const char *s = mpm_status_string(fresh[i]);
        int distinct = 1;
        snprintf(name, sizeof name, "status %u has its documented number", number[i]);
        expect_true(name, (unsigned)fresh[i] == number[i]);
        snprintf(name, sizeof name, "status string of %u is a description", number[i]);
        expect_detail(name, s != NULL && s[0] != '\0' && strcmp(s, "unknown status") != 0,
                      s != NULL ? s : "(null)");
        for (j = 0; j < sizeof fresh / sizeof fresh[0]; j++) {
            distinct &= j == i || strcmp(s, mpm_status_string(fresh[j])) != 0;
        }
        for (j = 0; j < sizeof older / sizeof older[0]; j++) {
            distinct &= strcmp(s, mpm_status_string(older[j])) != 0;
        }
        snprintf(name, sizeof name, "status string of %u differs from the others", number[i]);
        expect_true(name, distinct);
    }
}

/* ---- 1. aliasing ---------------------------------------------------------------------- */

#define GUARD_LEAD 4096
#define GUARD_TRAIL 4096
#define ALIAS_MAX 64

static void aliasing(void) {
    MpmWorldDef d = def_2d_effects(128);
    Host hx;
    MpmWorld *w;
    unsigned char *base, *mid, *end;
    MpmMaterialDef m = mpm_material_def_default();
    MpmParticlesView view;
    MpmIdRange ids;
    MpmStepReport report;
    uint32_t id = 0;
    size_t n, i, k;
    int a;
    mpm_real t[ALIAS_MAX], col[ALIAS_MAX], zeros[ALIAS_MAX];
    mpm_real px[ALIAS_MAX], py[ALIAS_MAX], vx[ALIAS_MAX], vy[ALIAS_MAX];
    mpm_real mass[ALIAS_MAX], vol[ALIAS_MAX];
    uint32_t mat[ALIAS_MAX];
    mpm_real out_r[4 * ALIAS_MAX];
    uint32_t out_u[ALIAS_MAX];
    size_t written;
    MpmParticleArrays arr, bad;
    const MpmVec3 zero = v3(0, 0, 0);
    char name[160];

    hx = host_new2("aliasing: setup", &d, GUARD_LEAD, GUARD_TRAIL);
    w = hx.w;
    track(w);
    g_guarded = &hx;
    base = (unsigned char *)(void *)w;
    end = base + hx.bytes;
    /* A 64-byte aligned address in the middle of the world. */
    mid = base + ((hx.bytes / 2) & ~(size_t)63);

    ACCEPTED("aliasing: setup material", 1, mpm_world_add_material(w, &m, &id));
    ACCEPTED("aliasing: setup box", 1,
             mpm_world_fill_box(w, v3(0.4, 0.4, 0), v3(0.5, 0.5, 0), id, v3(0.1, 0, 0), &ids));
    n = ids.count;
    expect_true("aliasing: setup box has 16 particles", ids.first == 0 && n == 16);
    for (i = 0; i < n; i++) {
        t[i] = R(300.0 + (double)i);
        zeros[i] = R(0.0);
    }
    ACCEPTED("aliasing: setup temperatures", 1,
             mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, t, n));
    ACCEPTED("aliasing: setup step", 1, mpm_world_step(w, R(1.0 / 256.0), &report));
    view = view_of(w);
    expect_true("aliasing: the view has every effect column",
                view.count == n && view.temperature && view.concentration && view.force[0] &&
                    view.force[1] && view.damping[0] && view.damping[1]);

    /* Input arrays inside the world. */
    REFUSED("aliasing: set_particle_scalar temperature from the temperature column + 1",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0,
                                          view.temperature + 1, n - 1));
    REFUSED("aliasing: set_particle_scalar temperature from the x column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, view.position[0],
                                          n));
    REFUSED("aliasing: set_particle_scalar concentration from the concentration column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_CONCENTRATION, 0,
                                          view.concentration, n));
    REFUSED("aliasing: set_particle_sources temperature from the temperature column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_sources(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, view.temperature,
                                           n));
    REFUSED("aliasing: set_particle_sources concentration from the y velocity column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_sources(w, MPM_SCALAR_FIELD_CONCENTRATION, 0,
                                           view.velocity[1], n));
    REFUSED("aliasing: set_particle_forces fx from the force column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_forces(w, 0, view.force[0], zeros, NULL, n));
    REFUSED("aliasing: set_particle_forces fy from the force column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_forces(w, 0, zeros, view.force[1], NULL, n));
    REFUSED("aliasing: set_particle_forces from the position columns",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_forces(w, 0, view.position[0], view.position[1], NULL, n));
    REFUSED("aliasing: set_particle_damping alpha_g from the damping column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_damping(w, 0, view.damping[0], zeros, n));
    REFUSED("aliasing: set_particle_damping alpha_p from the damping column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_damping(w, 0, zeros, view.damping[1], n));
    REFUSED("aliasing: set_particle_damping alpha_g from the mass column",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_damping(w, 0, view.mass, zeros, n));

    /* add_particles: caller-owned copies of the particles, then each array in turn from the
     * world's own column. */
    for (i = 0; i < n; i++) {
        px[i] = view.position[0][i];
        py[i] = view.position[1][i];
        vx[i] = view.velocity[0][i];
        vy[i] = view.velocity[1][i];
        mass[i] = view.mass[i];
        vol[i] = view.volume0[i];
        mat[i] = view.material[i];
    }
    arr.position[0] = px;
    arr.position[1] = py;
    arr.position[2] = NULL;
    arr.velocity[0] = vx;
    arr.velocity[1] = vy;
    arr.velocity[2] = NULL;
    arr.mass = mass;
    arr.volume = vol;
    arr.material = mat;
    for (k = 0; k < 7; k++) {
        static const char *what[7] = {"position[0]", "position[1]", "velocity[0]",
                                      "velocity[1]", "mass",        "volume",
                                      "material"};
        bad = arr;
        switch (k) {
        case 0: bad.position[0] = view.position[0]; break;
        case 1: bad.position[1] = view.position[1]; break;
        case 2: bad.velocity[0] = view.velocity[0]; break;
        case 3: bad.velocity[1] = view.velocity[1]; break;
        case 4: bad.mass = view.mass; break;
        case 5: bad.volume = view.volume0; break;
        default: bad.material = view.material; break;
        }
        snprintf(name, sizeof name, "aliasing: add_particles with arrays.%s from the world",
                 what[k]);
        REFUSED(name, MPM_STATUS_OVERLAPPING_MEMORY,
                mpm_world_add_particles(w, &bad, n, OUT(MpmIdRange)));
    }

    /* Arrays that straddle the world's ends (the caller's memory around it holds PATTERN,
     * finite reals). */
    REFUSED("aliasing: set_particle_scalar from 2 values before the world to 2 inside it",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0,
                                          (const mpm_real *)(const void *)base - 2, 4));
    REFUSED("aliasing: set_particle_scalar from the world's last value to 1 past it",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0,
                                          (const mpm_real *)(const void *)end - 1, 2));
    REFUSED("aliasing: set_particle_sources from 1 value before the world to 1 inside it",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_sources(w, MPM_SCALAR_FIELD_CONCENTRATION, 0,
                                           (const mpm_real *)(const void *)base - 1, 2));

    /* Read-only calls whose output lies in the world. */
    REFUSED("aliasing: mpm_world_bytes into the world's middle", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_bytes(w, (size_t *)(void *)mid));
    REFUSED("aliasing: mpm_world_bytes onto the world's magic number",
            MPM_STATUS_OVERLAPPING_MEMORY, mpm_world_bytes(w, (size_t *)(void *)base));
    REFUSED("aliasing: mpm_world_bytes into the world's last 8 bytes",
            MPM_STATUS_OVERLAPPING_MEMORY, mpm_world_bytes(w, (size_t *)(void *)(end - 8)));
    REFUSED("aliasing: get_def into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_get_def(w, (MpmWorldDef *)(void *)mid));
    REFUSED("aliasing: get_def straddling the world's start", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_get_def(w, (MpmWorldDef *)(void *)(base - 64)));
    REFUSED("aliasing: stable_dt into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_stable_dt(w, (mpm_real *)(void *)mid));
    REFUSED("aliasing: particles (view) into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_particles(w, (MpmParticlesView *)(void *)mid));
    REFUSED("aliasing: particles (view) straddling the world's start",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_particles(w, (MpmParticlesView *)(void *)(base - 64)));
    REFUSED("aliasing: diagnostics into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_diagnostics(w, (MpmDiagnostics *)(void *)mid));
    REFUSED("aliasing: diagnostics straddling the world's end", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_diagnostics(w, (MpmDiagnostics *)(void *)(end - 64)));
    REFUSED("aliasing: traction_count into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_traction_count(w, (size_t *)(void *)mid));
    REFUSED("aliasing: feedback_alpha into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_feedback_alpha(w, (double *)(void *)mid));

#define COPY_ALIAS(fn, T, per)                                                               \
    REFUSED("aliasing: " #fn " out into the world", MPM_STATUS_OVERLAPPING_MEMORY,           \
            fn(w, (T *)(void *)mid, (per) * n, OUT_AT(size_t, WRITTEN_AT)));                  \
    REFUSED("aliasing: " #fn " written_out into the world", MPM_STATUS_OVERLAPPING_MEMORY,   \
            fn(w, OUT(T), (per) * n, (size_t *)(void *)mid));                                \
    REFUSED("aliasing: " #fn " out from 8 bytes before the world into it",                   \
            MPM_STATUS_OVERLAPPING_MEMORY,                                                   \
            fn(w, (T *)(void *)(base - 8), (per) * n, OUT_AT(size_t, WRITTEN_AT)));           \
    REFUSED("aliasing: " #fn " out from the world's last bytes past its end",                \
            MPM_STATUS_OVERLAPPING_MEMORY,                                                   \
            fn(w, (T *)(void *)(end - 8), (per) * n, OUT_AT(size_t, WRITTEN_AT)))
    COPY_ALIAS(mpm_world_copy_positions, mpm_real, 2);
    COPY_ALIAS(mpm_world_copy_velocities, mpm_real, 2);
    COPY_ALIAS(mpm_world_copy_stress, mpm_real, 4);
    COPY_ALIAS(mpm_world_copy_jacobians, mpm_real, 1);
    COPY_ALIAS(mpm_world_copy_status, uint32_t, 1);
#undef COPY_ALIAS

    /* Mutating calls whose output lies in the world (their inputs valid, room left). */
    REFUSED("aliasing: add_material id_out into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_add_material(w, &m, (uint32_t *)(void *)mid));
    REFUSED("aliasing: add_particles ids_out into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_add_particles(w, &arr, n, (MpmIdRange *)(void *)mid));
    REFUSED("aliasing: fill_box ids_out into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_fill_box(w, v3(0.2, 0.2, 0), v3(0.25, 0.25, 0), 0, zero,
                               (MpmIdRange *)(void *)mid));
    REFUSED("aliasing: fill_disk ids_out into the world's last 8 bytes",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_fill_disk(w, v3(0.7, 0.7, 0), R(0.03), 0, zero,
                                (MpmIdRange *)(void *)(end - 8)));
    REFUSED("aliasing: add_tractions ids_out into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_add_tractions(w, 0, 2, MPM_FACE_Y_MAX, v3(0, -100, 0),
                                    (MpmIdRange *)(void *)mid));
    REFUSED("aliasing: step report_out into the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_step(w, R(1.0 / 256.0), (MpmStepReport *)(void *)mid));
    REFUSED("aliasing: step report_out straddling the world's start",
            MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_step(w, R(1.0 / 256.0), (MpmStepReport *)(void *)(base - 16)));

    /* init and open: world_out inside the memory handed in. */
    {
        MpmMemoryRequirements req;
        Block mem;
        Block copy = snapshot(w);
        uint64_t before;
        MpmWorld *o = NULL;
        if (mpm_memory_requirements(&d, &req) != MPM_STATUS_OK) {
            fail("aliasing: init setup", "mpm_memory_requirements refused");
        }
        mem = block_new(req.bytes, req.align);
        memset(mem.raw, PATTERN, mem.raw_len);
        REFUSED("aliasing: init world_out inside the memory", MPM_STATUS_OVERLAPPING_MEMORY,
                mpm_world_init(&d, mem.at, req.bytes, (MpmWorld **)(void *)(mem.at + 64)));
        REFUSED("aliasing: init world_out in the memory's last 8 bytes",
                MPM_STATUS_OVERLAPPING_MEMORY,
                mpm_world_init(&d, mem.at, req.bytes,
                               (MpmWorld **)(void *)(mem.at + req.bytes - 8)));
        expect_true("aliasing: the refused inits left the memory untouched",
                    pattern_intact(mem.raw, mem.raw_len));
        ACCEPTED("aliasing: control init with world_out outside the memory", 0,
                 mpm_world_init(&d, mem.at, req.bytes, &o));
        expect_true("aliasing: control init wrote the memory", !pattern_intact(mem.at, 64));
        free(mem.raw);

        before = fnv1a(copy.at, hx.bytes);
        REFUSED("aliasing: open world_out inside the copy", MPM_STATUS_OVERLAPPING_MEMORY,
                mpm_world_open(copy.at, hx.bytes, (MpmWorld **)(void *)(copy.at + 64)));
        REFUSED("aliasing: open world_out on the copy's magic number",
                MPM_STATUS_OVERLAPPING_MEMORY,
                mpm_world_open(copy.at, hx.bytes, (MpmWorld **)(void *)copy.at));
        expect_true("aliasing: the refused opens left the copy's bytes as they were",
                    fnv1a(copy.at, hx.bytes) == before);
        ACCEPTED("aliasing: control open with world_out outside the copy", 0,
                 mpm_world_open(copy.at, hx.bytes, &o));
        expect_true("aliasing: control open at the copy's address",
                    (void *)o == (void *)copy.at);
        free(copy.raw);
    }

    /* Controls: the same calls with caller-owned data and outputs. */
    view = view_of(w);
    for (i = 0; i + 1 < n; i++) {
        col[i] = view.temperature[i + 1];
    }
    ACCEPTED("aliasing: control set_particle_scalar from a copy of the temperature column + 1",
             1, mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, col, n - 1));
    view = view_of(w);
    {
        int same = 1;
        for (i = 0; i + 1 < n; i++) {
            same &= view.temperature[i] == col[i];
        }
        expect_true("aliasing: control temperatures are the copied values", same);
    }
    for (i = 0; i < n; i++) {
        col[i] = view.velocity[1][i];
    }
    ACCEPTED("aliasing: control set_particle_sources from a copy of the y velocity column", -1,
             mpm_world_set_particle_sources(w, MPM_SCALAR_FIELD_CONCENTRATION, 0, col, n));
    for (i = 0; i < n; i++) {
        col[i] = view.position[0][i];
    }
    ACCEPTED("aliasing: control set_particle_forces from copies of the position columns", 1,
             mpm_world_set_particle_forces(w, 0, col, py, NULL, n));
    ACCEPTED("aliasing: control set_particle_damping from a copy of the mass column", 1,
             mpm_world_set_particle_damping(w, 0, mass, zeros, n));
    ACCEPTED("aliasing: control set_particle_scalar from the 2 values just before the world",
             1,
             mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0,
                                           (const mpm_real *)(const void *)base - 2, 2));
    ACCEPTED("aliasing: control set_particle_scalar from the 2 values just after the world "
             "(particles 2 and 3)",
             1,
             mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 2,
                                           (const mpm_real *)(const void *)end, 2));
    ACCEPTED("aliasing: control add_particles from caller-owned copies", 1,
             mpm_world_add_particles(w, &arr, n, &ids));
    expect_true("aliasing: control add_particles ids", ids.first == n && ids.count == n);
    ACCEPTED("aliasing: control add_material", 1, mpm_world_add_material(w, &m, &id));
    ACCEPTED("aliasing: control fill_box", 1,
             mpm_world_fill_box(w, v3(0.2, 0.2, 0), v3(0.25, 0.25, 0), 0, zero, &ids));
    ACCEPTED("aliasing: control add_tractions", 1,
             mpm_world_add_tractions(w, 0, 2, MPM_FACE_Y_MAX, v3(0, -100, 0), &ids));
    ACCEPTED("aliasing: control step", 1, mpm_world_step(w, R(1.0 / 256.0), &report));
    n = particle_count(w);
    if (n > ALIAS_MAX) {
        fail("aliasing: controls", "more particles than the buffers hold");
    }

    /* Read-only controls, into caller memory and into the caller memory just around the
     * world (touching its ends, not overlapping). */
    ACCEPTED("aliasing: control mpm_world_bytes", 0, mpm_world_bytes(w, &written));
    ACCEPTED("aliasing: control mpm_world_bytes into the 8 bytes just before the world", 0,
             mpm_world_bytes(w, (size_t *)(void *)(base - 8)));
    ACCEPTED("aliasing: control mpm_world_bytes into the 8 bytes just after the world", 0,
             mpm_world_bytes(w, (size_t *)(void *)end));
    {
        size_t before_start, after_end;
        memcpy(&before_start, base - 8, sizeof before_start);
        memcpy(&after_end, end, sizeof after_end);
        expect_true("aliasing: control mpm_world_bytes values",
                    written == hx.bytes && before_start == hx.bytes && after_end == hx.bytes);
    }
    {
        MpmWorldDef back;
        MpmDiagnostics diag;
        mpm_real dt;
        double alpha;
        ACCEPTED("aliasing: control get_def", 0, mpm_world_get_def(w, &back));
        ACCEPTED("aliasing: control get_def just before the world", 0,
                 mpm_world_get_def(w, (MpmWorldDef *)(void *)(base - sizeof(MpmWorldDef))));
        ACCEPTED("aliasing: control stable_dt", 0, mpm_world_stable_dt(w, &dt));
        ACCEPTED("aliasing: control particles", 0, mpm_world_particles(w, &view));
        ACCEPTED("aliasing: control particles just after the world", 0,
                 mpm_world_particles(w, (MpmParticlesView *)(void *)end));
        ACCEPTED("aliasing: control diagnostics", 0, mpm_world_diagnostics(w, &diag));
        ACCEPTED("aliasing: control diagnostics just before the world", 0,
                 mpm_world_diagnostics(
                     w, (MpmDiagnostics *)(void *)(base - sizeof(MpmDiagnostics))));
        ACCEPTED("aliasing: control traction_count", 0, mpm_world_traction_count(w, &written));
        expect_true("aliasing: control traction_count is 2", written == 2);
        ACCEPTED("aliasing: control feedback_alpha", 0, mpm_world_feedback_alpha(w, &alpha));
        expect_true("aliasing: control feedback_alpha finite", isfinite(alpha));
    }
    ACCEPTED("aliasing: control copy_positions", 0,
             mpm_world_copy_positions(w, out_r, 2 * n, &written));
    ACCEPTED("aliasing: control copy_positions ending just before the world", 0,
             mpm_world_copy_positions(w, (mpm_real *)(void *)base - 2 * n, 2 * n, &written));
    ACCEPTED("aliasing: control copy_velocities starting just after the world", 0,
             mpm_world_copy_velocities(w, (mpm_real *)(void *)end, 2 * n, &written));
    ACCEPTED("aliasing: control copy_stress", 0,
             mpm_world_copy_stress(w, out_r, 4 * n, &written));
    ACCEPTED("aliasing: control copy_jacobians", 0,
             mpm_world_copy_jacobians(w, out_r, n, &written));
    ACCEPTED("aliasing: control copy_status", 0, mpm_world_copy_status(w, out_u, n, &written));
    expect_true("aliasing: control copy_status count", written == n);
    guards_reset();
    for (a = 0; a < 2; a++) {
        /* The world after all of it still steps. */
        snprintf(name, sizeof name, "aliasing: step %d after the checks", a + 1);
        ACCEPTED(name, 1, mpm_world_step(w, R(1.0 / 256.0), &report));
    }
    diag_check("aliasing: diagnostics finite after the checks", w);
    g_guarded = NULL;
    host_free(&hx);
}

/* ---- 2. not a world next to a page without access ------------------------------------- */

static void not_a_world_at_page_end(void) {
#ifdef HOSTILE_HAVE_MMAN
    long page = sysconf(_SC_PAGESIZE);
    unsigned char *p, *q;
    MpmWorld *w;
    MpmMaterialDef m = mpm_material_def_default();
    mpm_real vals[4] = {0, 0, 0, 0};
    uint32_t mats[4] = {0, 0, 0, 0};
    MpmParticleArrays arr;
    int round, k;
    char name[160];
    static const unsigned char magic[8] = {'M', 'P', 'M', 'G', 'I', 'M', 'P', 0};

    p = (unsigned char *)mmap(NULL, 2 * (size_t)page, PROT_READ | PROT_WRITE,
                              MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if ((void *)p == MAP_FAILED) {
        fail("not a world: setup", "mmap failed");
    }
    if (mprotect(p + page, (size_t)page, PROT_NONE) != 0) {
        fail("not a world: setup", "mprotect failed");
    }
    q = p + page - 64;
    w = (MpmWorld *)(void *)q;
    for (k = 0; k < 3; k++) {
        arr.position[k] = vals;
        arr.velocity[k] = vals;
    }
    arr.mass = vals;
    arr.volume = vals;
    arr.material = mats;

    for (round = 0; round < 2; round++) {
        const char *what = round == 0 ? "64 zero bytes" : "64 random bytes";
        if (round == 0) {
            memset(q, 0, 64);
        } else {
            do {
                for (k = 0; k < 64; k++) {
                    q[k] = (unsigned char)(rnd() & 0xFF);
                }
            } while (memcmp(q, magic, 8) == 0);
        }
#define NAW(fn, call)                                                                         \
    snprintf(name, sizeof name, "not a world (%s before a page without access): %s", what, fn); \
    REFUSED(name, MPM_STATUS_NOT_A_WORLD, call)
        NAW("mpm_world_bytes", mpm_world_bytes(w, OUT(size_t)));
        NAW("mpm_world_step", mpm_world_step(w, R(0.001), OUT(MpmStepReport)));
        NAW("mpm_world_particles", mpm_world_particles(w, OUT(MpmParticlesView)));
        NAW("mpm_world_diagnostics", mpm_world_diagnostics(w, OUT(MpmDiagnostics)));
        NAW("mpm_world_get_def", mpm_world_get_def(w, OUT(MpmWorldDef)));
        NAW("mpm_world_stable_dt", mpm_world_stable_dt(w, OUT(mpm_real)));
        NAW("mpm_world_add_material", mpm_world_add_material(w, &m, OUT(uint32_t)));
        NAW("mpm_world_add_particles", mpm_world_add_particles(w, &arr, 1, OUT(MpmIdRange)));
        NAW("mpm_world_fill_box", mpm_world_fill_box(w, v3(0.2, 0.2, 0), v3(0.3, 0.3, 0), 0,
                                                     v3(0, 0, 0), OUT(MpmIdRange)));
        NAW("mpm_world_fill_disk", mpm_world_fill_disk(w, v3(0.2, 0.2, 0), R(0.02), 0,
                                                       v3(0, 0, 0), OUT(MpmIdRange)));
        NAW("mpm_world_fill_sphere", mpm_world_fill_sphere(w, v3(0.2, 0.2, 0.2), R(0.02), 0,
                                                           v3(0, 0, 0), OUT(MpmIdRange)));
        NAW("mpm_world_copy_positions",
            mpm_world_copy_positions(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        NAW("mpm_world_copy_velocities",
            mpm_world_copy_velocities(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        NAW("mpm_world_copy_stress",
            mpm_world_copy_stress(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        NAW("mpm_world_copy_jacobians",
            mpm_world_copy_jacobians(w, OUT(mpm_real), 16, OUT_AT(size_t, WRITTEN_AT)));
        NAW("mpm_world_copy_status",
            mpm_world_copy_status(w, OUT(uint32_t), 16, OUT_AT(size_t, WRITTEN_AT)));
        NAW("mpm_world_set_particle_forces",
            mpm_world_set_particle_forces(w, 0, vals, vals, vals, 1));
        {
            const mpm_real *h9[9] = {vals, vals, vals, vals, vals, vals, vals, vals, vals};
            NAW("mpm_world_set_displacement_gradient",
                mpm_world_set_displacement_gradient(w, 0, h9, 1));
        }
        NAW("mpm_world_set_particle_damping",
            mpm_world_set_particle_damping(w, 0, vals, vals, 1));
        NAW("mpm_world_set_particle_scalar",
            mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, vals, 1));
        NAW("mpm_world_set_particle_sources",
            mpm_world_set_particle_sources(w, MPM_SCALAR_FIELD_CONCENTRATION, 0, vals, 1));
        NAW("mpm_world_add_tractions",
            mpm_world_add_tractions(w, 0, 1, MPM_FACE_Y_MAX, v3(0, -1, 0), OUT(MpmIdRange)));
        NAW("mpm_world_add_surface_tractions",
            mpm_world_add_surface_tractions(w, 0, 1, v3(0, 1, 0), R(0.1), v3(0, -1, 0),
                                            OUT(MpmIdRange)));
        NAW("mpm_world_add_follower_tractions",
            mpm_world_add_follower_tractions(w, 0, 1, v3(0, 1, 0), R(0.1), v3(-1, 0, 0),
                                             OUT(MpmIdRange)));
        NAW("mpm_world_set_traction_schedule", mpm_world_set_traction_schedule(w, 0, 1, 1));
        NAW("mpm_world_clear_tractions", mpm_world_clear_tractions(w));
        NAW("mpm_world_remove_tractions", mpm_world_remove_tractions(w, 0, 1));
        NAW("mpm_world_traction_count", mpm_world_traction_count(w, OUT(size_t)));
        NAW("mpm_world_feedback_alpha", mpm_world_feedback_alpha(w, OUT(double)));
#undef NAW
        /* Too short for a header and not a world: either refusal is right. */
        snprintf(name, sizeof name,
                 "not a world (%s before a page without access): mpm_world_open of its 64 bytes",
                 what);
        {
            MpmStatus s = (out_reset(), mpm_world_open(q, 64, OUT(MpmWorld *)));
            REFUSED(name, s == MPM_STATUS_NOT_A_WORLD ? s : MPM_STATUS_BUFFER_TOO_SMALL, s);
        }
    }
    /* 8 bytes before the page: misaligned, refused before anything is read. */
    REFUSED("not a world: 8 bytes before a page without access (misaligned)",
            MPM_STATUS_BUFFER_MISALIGNED,
            mpm_world_bytes((MpmWorld *)(void *)(p + page - 8), OUT(size_t)));
    munmap(p, 2 * (size_t)page);
#else
    expect_true("not a world next to a page without access: skipped (no mmap)", 1);
#endif
}

/* ---- 3. the thermostat cannot brick a world; 4. seeding validates masses -------------- */

/* A 2D world of 10 m cells (so that a sub-cell's volume, 25 m^2, times a density of half the
 * largest real overflows), with the thermostat. */
static MpmWorldDef def_big_2d(void) {
    MpmWorldDef d = def_2d(256);
    d.cell_size = R(10.0);
    d.effects.damping.declared = 1;
    d.effects.damping.feedback.declared = 1;
    d.effects.damping.feedback.gain = R(1.0);
    d.effects.damping.feedback.max_alpha = R(8.0);
    return d;
}

static void open_refused_copy(const char *name, MpmStatus want, Block *copy, size_t len) {
    uint64_t before = fnv1a(copy->at, len);
    REFUSED(name, want, mpm_world_open(copy->at, len, OUT(MpmWorld *)));
    if (fnv1a(copy->at, len) != before) {
        fail(name, "the refused open changed the copy's bytes");
    }
}

static void thermostat_world(void) {
    MpmWorldDef d = def_big_2d(), d3;
    Host hb, h3;
    MpmMaterialDef m = mpm_material_def_default(), huge = mpm_material_def_default();
    MpmIdRange ids;
    MpmStepReport report;
    MpmParticlesView view;
    MpmWorld *o = NULL;
    uint32_t id = 0, id_huge = 0;
    Block copy;
    double alpha = -1.0;
    int step;
    char name[128];

    huge.density = REAL_MAX / R(2.0);
    {
        /* The sub-cell volume (h / 2)^2 times that density overflows in mpm_real. */
        volatile mpm_real vol = R(5.0) * R(5.0);
        volatile mpm_real mass = vol * huge.density;
        expect_true("thermostat: setup 25 m^2 times half the largest real overflows",
                    isinf(mass));
    }

    hb = host_new("thermostat: setup", &d);
    track(hb.w);
    ACCEPTED("thermostat: material", 1, mpm_world_add_material(hb.w, &m, &id));
    ACCEPTED("thermostat: material of half the largest real's density (valid)", 1,
             mpm_world_add_material(hb.w, &huge, &id_huge));
    ACCEPTED("thermostat: box", 1,
             mpm_world_fill_box(hb.w, v3(50, 50, 0), v3(100, 100, 0), id, v3(1, 0, 0), &ids));
    expect_true("thermostat: box of 100 particles", ids.count == 100);
    for (step = 0; step < 3; step++) {
        snprintf(name, sizeof name, "thermostat: step %d", step + 1);
        ACCEPTED(name, 1, mpm_world_step(hb.w, R(1.0 / 60.0), &report));
    }

    /* A snapshot with one NaN velocity does not open. */
    view = view_of(hb.w);
    copy = snapshot(hb.w);
    *(mpm_real *)(void *)in_copy(&copy, hb.w, view.velocity[0] + 7) = R(NAN);
    open_refused_copy("thermostat: snapshot with a NaN velocity", MPM_STATUS_INVALID_STATE,
                      &copy, hb.bytes);
    memcpy(copy.at, hb.w, hb.bytes);
    ACCEPTED("thermostat: the intact snapshot opens", 0, mpm_world_open(copy.at, hb.bytes, &o));
    free(copy.raw);

    /* The original still steps, reads and reopens. */
    ACCEPTED("thermostat: the original steps", 1, mpm_world_step(hb.w, R(1.0 / 60.0), &report));
    diag_check("thermostat: the original's diagnostics are finite", hb.w);
    ACCEPTED("thermostat: the original reopens in place", 0,
             mpm_world_open(hb.w, hb.bytes, &o));
    expect_true("thermostat: the reopened world is the original", o == hb.w);

    /* Fills whose mass overflows are refused and change nothing. */
    REFUSED("thermostat: fill_box whose mass overflows to infinity", MPM_STATUS_NON_FINITE_INPUT,
            mpm_world_fill_box(hb.w, v3(120, 120, 0), v3(140, 140, 0), id_huge, v3(0, 0, 0),
                               OUT(MpmIdRange)));
    REFUSED("thermostat: fill_disk whose mass overflows to infinity",
            MPM_STATUS_NON_FINITE_INPUT,
            mpm_world_fill_disk(hb.w, v3(150, 150, 0), R(15.0), id_huge, v3(0, 0, 0),
                                OUT(MpmIdRange)));
    for (step = 0; step < 3; step++) {
        snprintf(name, sizeof name, "thermostat: step %d after the refused fills", step + 1);
        ACCEPTED(name, 1, mpm_world_step(hb.w, R(1.0 / 60.0), &report));
    }
    diag_check("thermostat: diagnostics finite after the refused fills", hb.w);
    ACCEPTED("thermostat: feedback_alpha", 0, mpm_world_feedback_alpha(hb.w, &alpha));
    {
        char detail[64];
        snprintf(detail, sizeof detail, "alpha %g", alpha);
        expect_detail("thermostat: alpha finite and in [0, max_alpha]",
                      isfinite(alpha) && alpha >= 0.0 && alpha <= 8.0, detail);
    }
    active_check("thermostat: every active particle finite with J in the band", hb.w);
    host_free(&hb);

    /* 3D: a sub-cell of 125 m^3. */
    d3 = def_big_2d();
    d3.dimension = MPM_DIMENSION_SPACE3D;
    d3.cells[0] = 8;
    d3.cells[1] = 8;
    d3.cells[2] = 8;
    h3 = host_new("thermostat 3D: setup", &d3);
    track(h3.w);
    ACCEPTED("thermostat 3D: material", 1, mpm_world_add_material(h3.w, &m, &id));
    ACCEPTED("thermostat 3D: material of half the largest real's density", 1,
             mpm_world_add_material(h3.w, &huge, &id_huge));
    REFUSED("thermostat 3D: fill_sphere whose mass overflows to infinity",
            MPM_STATUS_NON_FINITE_INPUT,
            mpm_world_fill_sphere(h3.w, v3(40, 40, 40), R(12.0), id_huge, v3(0, 0, 0),
                                  OUT(MpmIdRange)));
    REFUSED("thermostat 3D: fill_box whose mass overflows to infinity",
            MPM_STATUS_NON_FINITE_INPUT,
            mpm_world_fill_box(h3.w, v3(20, 20, 20), v3(30, 30, 30), id_huge, v3(0, 0, 0),
                               OUT(MpmIdRange)));
    ACCEPTED("thermostat 3D: control fill_sphere of the ordinary material", 1,
             mpm_world_fill_sphere(h3.w, v3(40, 40, 40), R(12.0), id, v3(0, 0, 0), &ids));
    ACCEPTED("thermostat 3D: step", 1, mpm_world_step(h3.w, R(1.0 / 60.0), &report));
    diag_check("thermostat 3D: diagnostics finite", h3.w);
    host_free(&h3);
}

static void seeding_underflow(void) {
    MpmWorldDef d = def_2d(64);
    Host ht;
    MpmMaterialDef tiny = mpm_material_def_default(), m = mpm_material_def_default();
    MpmIdRange ids;
    uint32_t id_tiny = 0, id = 0;
    const double h = TINY_CELL;
    MpmStepReport report;

    tiny.density = REAL_MIN;
    tiny.youngs_modulus = R(TINY_MODULUS);
    {
        volatile mpm_real half = R(h / 2.0);
        volatile mpm_real vol = half * half;
        volatile mpm_real mass = vol * tiny.density;
        expect_true("seeding: setup the tiny sub-cell volume times the smallest normal density "
                    "underflows to 0",
                    vol > R(0.0) && mass == R(0.0));
    }
    d.cell_size = R(h);
    ht = host_new("seeding: setup", &d);
    track(ht.w);
    ACCEPTED("seeding: material of the smallest normal density (valid)", 1,
             mpm_world_add_material(ht.w, &tiny, &id_tiny));
    ACCEPTED("seeding: ordinary material", 1, mpm_world_add_material(ht.w, &m, &id));
    REFUSED("seeding: fill_box whose mass underflows to 0",
            MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME,
            mpm_world_fill_box(ht.w, v3(8 * h, 8 * h, 0), v3(10 * h, 10 * h, 0), id_tiny,
                               v3(0, 0, 0), OUT(MpmIdRange)));
    REFUSED("seeding: fill_disk whose mass underflows to 0",
            MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME,
            mpm_world_fill_disk(ht.w, v3(10 * h, 10 * h, 0), R(2 * h), id_tiny, v3(0, 0, 0),
                                OUT(MpmIdRange)));
    ACCEPTED("seeding: control fill_box of the ordinary material in the tiny cells", 1,
             mpm_world_fill_box(ht.w, v3(8 * h, 8 * h, 0), v3(10 * h, 10 * h, 0), id,
                                v3(0, 0, 0), &ids));
    expect_true("seeding: control box has 16 particles", ids.count == 16);
    ACCEPTED("seeding: 2D fill_box with NaN z in both corners and the velocity", 1,
             mpm_world_fill_box(ht.w, v3(4 * h, 4 * h, NAN), v3(6 * h, 6 * h, NAN), id,
                                v3(0, 0, NAN), &ids));
    expect_true("seeding: the box with NaN z has 16 particles", ids.count == 16);
    ACCEPTED("seeding: 2D fill_box with infinite z", 1,
             mpm_world_fill_box(ht.w, v3(12 * h, 4 * h, -INFINITY), v3(14 * h, 6 * h, INFINITY),
                                id, v3(0, 0, INFINITY), &ids));
    {
        MpmParticlesView view = view_of(ht.w);
        size_t i;
        int finite = view.position[2] == NULL && view.velocity[2] == NULL &&
                     view.position_low[2] == NULL && view.position_low[0] != NULL &&
                     view.position_low[1] != NULL;
        for (i = 0; finite && i < view.count; i++) {
            finite &= isfinite(view.position_low[0][i]) && isfinite(view.position_low[1][i]) &&
                      isfinite(view.position[0][i]) && isfinite(view.position[1][i]) &&
                      isfinite(view.velocity[0][i]) && isfinite(view.velocity[1][i]) &&
                      isfinite(view.mass[i]) && view.mass[i] > R(0.0);
        }
        expect_true("seeding: every seeded particle finite with a positive mass", finite);
    }
    {
        mpm_real stable = R(0.0);
        ACCEPTED("seeding: stable_dt of the tiny world", 0, mpm_world_stable_dt(ht.w, &stable));
        expect_true("seeding: the tiny world's stable dt is finite and positive",
                    isfinite(stable) && stable > R(0.0));
        ACCEPTED("seeding: step of the tiny world", 1,
                 mpm_world_step(ht.w, stable * R(2.0), &report));
    }
    diag_check("seeding: diagnostics finite", ht.w);
    host_free(&ht);
}

/* ---- 5. open checks the state; random corruption ------------------------------------- */

/* The world the snapshot checks edit: every effect, 288 particles, tractions, a few steps. */
static Host state_world(void) {
    MpmWorldDef d = def_2d_effects(320);
    Host hs;
    MpmMaterialDef m = mpm_material_def_default();
    MpmIdRange ids;
    MpmStepReport report;
    uint32_t id = 0;
    mpm_real t[320], f[320], alpha[320];
    size_t n, i;
    int step;

    d.max_substeps = 64;
    hs = host_new("state: setup", &d);
    track(hs.w);
    m.conductivity = R(0.5);
    m.diffusivity = R(1e-4);
    ACCEPTED("state: material", 1, mpm_world_add_material(hs.w, &m, &id));
    ACCEPTED("state: box", 1,
             mpm_world_fill_box(hs.w, v3(0.2, 0.2, 0), v3(0.8, 0.5, 0), id, v3(0.2, -0.5, 0),
                                &ids));
    n = ids.count;
    expect_true("state: box of 288 particles", n == 288);
    for (i = 0; i < n; i++) {
        t[i] = R(290.0 + 0.1 * (double)i);
        f[i] = R(1e-4 * (double)(i % 7));
        alpha[i] = R(0.01 * (double)(i % 5));
    }
    ACCEPTED("state: temperatures", 1,
             mpm_world_set_particle_scalar(hs.w, MPM_SCALAR_FIELD_TEMPERATURE, 0, t, n));
    ACCEPTED("state: concentrations", 1,
             mpm_world_set_particle_scalar(hs.w, MPM_SCALAR_FIELD_CONCENTRATION, 0, f, n));
    ACCEPTED("state: heat sources", 1,
             mpm_world_set_particle_sources(hs.w, MPM_SCALAR_FIELD_TEMPERATURE, 0, t, n));
    ACCEPTED("state: forces", 1, mpm_world_set_particle_forces(hs.w, 0, f, f, NULL, n));
    ACCEPTED("state: damping", 1, mpm_world_set_particle_damping(hs.w, 0, alpha, alpha, n));
    ACCEPTED("state: tractions", 1,
             mpm_world_add_tractions(hs.w, 0, 4, MPM_FACE_Y_MAX, v3(0, -50, 0), &ids));
    for (step = 0; step < 4; step++) {
        char name[64];
        snprintf(name, sizeof name, "state: step %d", step + 1);
        ACCEPTED(name, 1, mpm_world_step(hs.w, R(1e-3), &report));
    }
    return hs;
}

typedef enum { EDIT_REAL, EDIT_U32 } EditKind;

static void state_edits(const Host *hs) {
    const MpmWorld *w = hs->w;
    MpmParticlesView view = view_of(w);
    Block copy = snapshot(w);
    MpmWorld *o = NULL;
    MpmStepReport report;
    const size_t k = 37;
    size_t e;
    char name[160];
    struct {
        const char *what;
        const void *at;
        EditKind kind;
        double real;
        uint32_t u;
    } edits[32];
    size_t n_edits = 0;

#define EDIT_R(label, ptr, value)        \
    edits[n_edits].what = (label);       \
    edits[n_edits].at = (ptr);           \
    edits[n_edits].kind = EDIT_REAL;     \
    edits[n_edits].real = (value);       \
    edits[n_edits].u = 0;                \
    n_edits++
#define EDIT_U(label, ptr, value)        \
    edits[n_edits].what = (label);       \
    edits[n_edits].at = (ptr);           \
    edits[n_edits].kind = EDIT_U32;      \
    edits[n_edits].real = 0.0;           \
    edits[n_edits].u = (value);          \
    n_edits++

    expect_true("state: the edited particle is active",
                view.count == 288 && view.status[k] == MPM_PARTICLE_STATUS_ACTIVE);
    EDIT_R("a NaN mass", view.mass + k, NAN);
    EDIT_R("a negative mass", view.mass + k, -1.0);
    EDIT_R("a zero mass", view.mass + k, 0.0);
    EDIT_R("an infinite mass", view.mass + k, INFINITY);
    EDIT_R("a NaN volume", view.volume0 + k, NAN);
    EDIT_R("a zero volume", view.volume0 + k, 0.0);
    EDIT_U("an unknown status (7)", view.status + k, 7u);
    EDIT_U("an unknown status (0xFFFFFFFF)", view.status + k, 0xFFFFFFFFu);
    EDIT_U("an unknown material id (1, of 1 material)", view.material + k, 1u);
    EDIT_U("an unknown material id (0xFFFFFFFF)", view.material + k, 0xFFFFFFFFu);
    EDIT_R("a NaN x position", view.position[0] + k, NAN);
    EDIT_R("a y position of +inf", view.position[1] + k, INFINITY);
    EDIT_R("an x position far outside the grid (1e6)", view.position[0] + k, 1e6);
    EDIT_R("a y position far below the grid (-1e6)", view.position[1] + k, -1e6);
    EDIT_R("a NaN x velocity", view.velocity[0] + k, NAN);
    EDIT_R("a y velocity of -inf", view.velocity[1] + k, -INFINITY);
    EDIT_R("a NaN stress xx", view.stress[0] + k, NAN);
    EDIT_R("an infinite stress zz", view.stress[3] + k, INFINITY);
    EDIT_R("a NaN displacement gradient H_xy", view.displacement_gradient[1] + k, NAN);
    EDIT_R("an inverted F (H_xx = -2)", view.displacement_gradient[0] + k, -2.0);
    EDIT_R("a NaN temperature", view.temperature + k, NAN);
    EDIT_R("an infinite concentration", view.concentration + k, INFINITY);
    EDIT_R("a NaN particle force", view.force[0] + k, NAN);
    EDIT_R("an infinite particle damping", view.damping[0] + k, INFINITY);
    /* The last particle too (the columns' tail). */
    EDIT_R("a NaN mass of the last particle", view.mass + (view.count - 1), NAN);
#undef EDIT_R
#undef EDIT_U

    for (e = 0; e < n_edits; e++) {
        unsigned char *at = in_copy(&copy, w, edits[e].at);
        memcpy(copy.at, w, hs->bytes);
        if (edits[e].kind == EDIT_REAL) {
            *(mpm_real *)(void *)at = (mpm_real)edits[e].real;
        } else {
            *(uint32_t *)(void *)at = edits[e].u;
        }
        snprintf(name, sizeof name, "open: snapshot with %s", edits[e].what);
        open_refused_copy(name, MPM_STATUS_INVALID_STATE, &copy, hs->bytes);
    }
    memcpy(copy.at, w, hs->bytes);
    ACCEPTED("open: the unedited snapshot opens", 0, mpm_world_open(copy.at, hs->bytes, &o));
    expect_true("open: the unedited snapshot opens at its address", (void *)o == (void *)copy.at);
    ACCEPTED("open: the unedited snapshot steps", 0, mpm_world_step(o, R(1e-3), &report));
    diag_check("open: the unedited snapshot's diagnostics are finite", o);
    free(copy.raw);
}

/* Whether every active particle's values are moderate (|x| <= 1e60): in double precision the
 * diagnostics of a state with, say, a finite velocity of 1e200 (valid: the contract asks only
 * for finite values) overflow, so their finiteness is required only for moderate states. The
 * strain energy reads the temperature and concentration too, and the material's parameters
 * (moduli, expansion and swelling coefficients), which the view does not show: a thermal
 * expansion coefficient corrupted to a huge finite value (so valid) leaves F moderate and made
 * the energy overflow (a stress of -5.7e272 in the round that found it). The stress carries
 * them (sigma ~ E eps, W ~ E eps^2 / 2), so a moderate stress stands for them. In single
 * precision every finite value is moderate. */
static int state_moderate(const MpmWorld *w) {
#ifdef MPM_GIMP_F64
    MpmParticlesView v;
    size_t i;
    int a;
    const double big = 1e60;
    if (mpm_world_particles(w, &v) != MPM_STATUS_OK) {
        return 0;
    }
    for (i = 0; i < v.count; i++) {
        if (v.status[i] != MPM_PARTICLE_STATUS_ACTIVE) {
            continue;
        }
        if (fabs(v.mass[i]) > big || fabs(v.volume0[i]) > big) {
            return 0;
        }
        if ((v.temperature != NULL && fabs(v.temperature[i]) > big) ||
            (v.concentration != NULL && fabs(v.concentration[i]) > big)) {
            return 0;
        }
        for (a = 0; a < 6; a++) {
            if (v.stress[a] != NULL && fabs(v.stress[a][i]) > big) {
                return 0;
            }
        }
        for (a = 0; a < 2; a++) {
            if (fabs(v.velocity[a][i]) > big || fabs(v.position[a][i]) > big) {
                return 0;
            }
        }
        for (a = 0; a < 9; a++) {
            if (v.displacement_gradient[a] != NULL && fabs(v.displacement_gradient[a][i]) > big) {
                return 0;
            }
        }
    }
    return 1;
#else
    (void)w;
    return 1;
#endif
}

#define CORRUPTION_ROUNDS 5000

static void random_corruption(const Host *hs) {
    const MpmWorld *w = hs->w;
    const size_t bytes = hs->bytes;
    Block master = snapshot(w), copy = block_new(bytes, 64), ref = block_new(bytes, 64);
    MpmParticlesView view = view_of(w);
    /* Half of the flips go to the header and the tables before the particle columns. */
    const size_t front =
        (size_t)((const unsigned char *)view.position[0] - (const unsigned char *)(const void *)w);
    unsigned long opened = 0, stepped = 0, limited = 0, not_world = 0, invalid = 0, small = 0;
    unsigned long round;
    char name[96], why[512], detail[256];

    for (round = 0; round < CORRUPTION_ROUNDS; round++) {
        unsigned flips = 1 + rnd() % 8, f;
        MpmWorld *o = NULL;
        MpmStatus s;
        memcpy(copy.at, master.at, bytes);
        for (f = 0; f < flips; f++) {
            size_t at = (rnd() & 1) ? (size_t)rnd() % front : (size_t)rnd() % bytes;
            copy.at[at] ^= (unsigned char)(1 + rnd() % 255);
        }
        memcpy(ref.at, copy.at, bytes);
        snprintf(name, sizeof name, "corruption round %lu", round);
        s = mpm_world_open(copy.at, bytes, &o);
        if (s == MPM_STATUS_NOT_A_WORLD || s == MPM_STATUS_INVALID_STATE ||
            s == MPM_STATUS_BUFFER_TOO_SMALL) {
            not_world += s == MPM_STATUS_NOT_A_WORLD;
            invalid += s == MPM_STATUS_INVALID_STATE;
            small += s == MPM_STATUS_BUFFER_TOO_SMALL;
            if (memcmp(copy.at, ref.at, bytes) != 0) {
                fail(name, "the refused open changed the copy's bytes");
            }
            continue;
        }
        if (s != MPM_STATUS_OK) {
            status_fail(name, "mpm_world_open answered a status outside the contract", s);
        }
        opened++;
        if ((void *)o != (void *)copy.at) {
            fail(name, "the opened world is not at the copy's address");
        }
        if (memcmp(copy.at, ref.at, bytes) != 0) {
            fail(name, "mpm_world_open changed the copy's bytes");
        }
        {
            MpmStepReport report;
            MpmDiagnostics diag;
            s = mpm_world_step(o, R(1e-4), &report);
            if (s == MPM_STATUS_SUBSTEP_LIMIT) {
                limited++;
                if (memcmp(copy.at, ref.at, bytes) != 0) {
                    fail(name, "a step refused with MPM_STATUS_SUBSTEP_LIMIT changed the world");
                }
            } else if (s == MPM_STATUS_OK) {
                stepped++;
                if (!active_state_ok(o, why, sizeof why)) {
                    fail(name, why);
                }
            } else {
                status_fail(name, "mpm_world_step of an opened world answered", s);
            }
            s = mpm_world_diagnostics(o, &diag);
            if (s != MPM_STATUS_OK) {
                status_fail(name, "mpm_world_diagnostics of an opened world answered", s);
            }
            if (!isfinite(diag.time) ||
                (state_moderate(o) && !(isfinite(diag.mass) && isfinite(diag.kinetic) &&
                                        isfinite(diag.strain) && isfinite(diag.potential)))) {
                snprintf(why, sizeof why,
                         "diagnostics not finite after the step (%s): time %g mass %g kinetic %g "
                         "strain %g potential %g",
                         mpm_status_string(s), diag.time, diag.mass, diag.kinetic, diag.strain,
                         diag.potential);
                fail(name, why);
            }
        }
    }
    snprintf(detail, sizeof detail,
             "%d copies: %lu opened (%lu stepped, %lu at the substep limit), %lu not a world, "
             "%lu invalid state, %lu buffer too small",
             CORRUPTION_ROUNDS, opened, stepped, limited, not_world, invalid, small);
    expect_detail("corruption: every damaged copy opened and stepped, or was refused without "
                  "writing",
                  opened + not_world + invalid + small == CORRUPTION_ROUNDS, detail);
    expect_true("corruption: some copies opened and some were refused as INVALID_STATE",
                opened > 0 && invalid > 0 && not_world > 0);
    free(master.raw);
    free(copy.raw);
    free(ref.raw);
}

/* ---- 6. runaway ----------------------------------------------------------------------- */

/* Classic MPM: linear hats, USL, a stick floor; an elastic block (0.4 x 0.2 m, 128 particles)
 * dropped from rest at `y0`. The scheme is unstable (cell crossing, light nodes at the block's
 * edges): particles' J runs away and they freeze, while others stay active. After every step
 * the report's flags must agree with its counts and every active particle must be finite with
 * J in the band. */
static void runaway_run(const char *label, mpm_real max_volume_ratio, double y0, int steps,
                        int want_runaway) {
    MpmWorldDef d = def_2d(256);
    Host hr;
    MpmMaterialDef m = mpm_material_def_default();
    MpmIdRange ids;
    MpmStepReport report;
    uint32_t id = 0;
    unsigned long frozen = 0, runaway = 0, frozen_steps = 0, runaway_steps = 0;
    unsigned long frozen_only_steps = 0;
    int step;
    char name[256], why[256], detail[256];
    Block copy;
    MpmWorld *o = NULL;

    d.shape = MPM_SHAPE_LINEAR;
    d.update_order = MPM_UPDATE_ORDER_USL;
    d.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    d.max_volume_ratio = max_volume_ratio;
    snprintf(name, sizeof name, "%s: setup", label);
    hr = host_new(name, &d);
    if (mpm_world_add_material(hr.w, &m, &id) != MPM_STATUS_OK ||
        mpm_world_fill_box(hr.w, v3(0.3, y0, 0), v3(0.7, y0 + 0.2, 0), id, v3(0, 0, 0), &ids) !=
            MPM_STATUS_OK) {
        fail(name, "the material or the box was refused");
    }
    for (step = 0; step < steps; step++) {
        MpmStatus s = mpm_world_step(hr.w, R(1.0 / 500.0), &report);
        int froze, ran;
        if (s != MPM_STATUS_OK) {
            snprintf(name, sizeof name, "%s: step %d", label, step);
            status_fail(name, "the step was refused", s);
        }
        froze = (report.flags & MPM_STEP_FLAG_FROZE) != 0;
        ran = (report.flags & MPM_STEP_FLAG_RUNAWAY) != 0;
        if (froze != (report.frozen > 0) || ran != (report.runaway > 0) ||
            report.runaway > report.frozen ||
            (report.flags & ~(uint32_t)(MPM_STEP_FLAG_FROZE | MPM_STEP_FLAG_RUNAWAY)) != 0) {
            snprintf(name, sizeof name, "%s: step %d", label, step);
            snprintf(why, sizeof why, "report frozen %u runaway %u flags 0x%x disagree", report.frozen,
                     report.runaway, (unsigned)report.flags);
            fail(name, why);
        }
        if (!active_state_ok(hr.w, why, sizeof why)) {
            snprintf(name, sizeof name, "%s: step %d", label, step);
            fail(name, why);
        }
        frozen += report.frozen;
        runaway += report.runaway;
        frozen_steps += report.frozen > 0;
        runaway_steps += report.runaway > 0;
        frozen_only_steps += report.frozen > report.runaway;
    }
    snprintf(name, sizeof name,
             "%s: %d steps accepted, each report's flags agreeing with its counts and every "
             "active particle finite with J in the band after each",
             label, steps);
    snprintf(detail, sizeof detail,
             "%lu frozen (in %lu steps), %lu of them runaway (in %lu steps; %lu steps froze "
             "others), %lu of %u particles active at the end",
             frozen, frozen_steps, runaway, runaway_steps, frozen_only_steps,
             (unsigned long)(ids.count - frozen), ids.count);
    expect_detail(name, 1, detail);
    if (want_runaway) {
        snprintf(name, sizeof name, "%s: the tight band froze particles as runaway", label);
        expect_detail(name, runaway > 0, detail);
    }
    snprintf(name, sizeof name, "%s: every active particle finite with J in the band", label);
    active_check(name, hr.w);
    snprintf(name, sizeof name, "%s: diagnostics finite", label);
    diag_check(name, hr.w);
    copy = snapshot(hr.w);
    snprintf(name, sizeof name, "%s: the world the run left reopens from a snapshot", label);
    ACCEPTED(name, 0, mpm_world_open(copy.at, hr.bytes, &o));
    snprintf(name, sizeof name, "%s: the reopened snapshot steps", label);
    ACCEPTED(name, 0, mpm_world_step(o, R(1.0 / 500.0), &report));
    free(copy.raw);
    host_free(&hr);
}

/* ---- 7. bounded calls ----------------------------------------------------------------- */

/* A steel block (E 200 GPa, nu 0.3, 7850 kg/m^3) of 400 particles on the default grid (100 x
 * 100 cells of 1 cm): about 8.5e-7 s stable. */
static Host steel_world(uint32_t max_substeps) {
    MpmWorldDef d = mpm_world_def_default();
    Host h;
    MpmMaterialDef m = mpm_material_def_default();
    MpmIdRange ids;
    uint32_t id = 0;
    d.particle_capacity = 512;
    d.material_capacity = 1;
    d.max_substeps = max_substeps;
    h = host_new("steel: setup", &d);
    m.youngs_modulus = R(200e9);
    m.poisson_ratio = R(0.3);
    m.density = R(7850.0);
    if (mpm_world_add_material(h.w, &m, &id) != MPM_STATUS_OK ||
        mpm_world_fill_box(h.w, v3(0.45, 0.45, 0), v3(0.55, 0.55, 0), id, v3(0, 0, 0), &ids) !=
            MPM_STATUS_OK ||
        ids.count != 400) {
        fail("steel: setup", "the material or the box was refused");
    }
    return h;
}

static void steel(void) {
    Host h = steel_world(1000), hb, hs;
    MpmStepReport report;
    mpm_real stable = R(0.0);
    uint32_t s_needed;
    char detail[160];

    track(h.w);
    ACCEPTED("steel: stable_dt", 0, mpm_world_stable_dt(h.w, &stable));
    snprintf(detail, sizeof detail, "stable dt %g s, 1/60 s needs %.0f substeps", (double)stable,
             ceil((1.0 / 60.0) / (double)stable));
    expect_detail("steel: 1/60 s needs more than 1000 substeps",
                  (1.0 / 60.0) / (double)stable > 1000.0, detail);
    REFUSED("steel: step of 1/60 s (limit 1000)", MPM_STATUS_SUBSTEP_LIMIT,
            mpm_world_step(h.w, R(1.0 / 60.0), OUT(MpmStepReport)));
    REFUSED("steel: step of 1/600 s (limit 1000)", MPM_STATUS_SUBSTEP_LIMIT,
            mpm_world_step(h.w, R(1.0 / 600.0), OUT(MpmStepReport)));
    ACCEPTED("steel: step of 1e-4 s (limit 1000)", 1, mpm_world_step(h.w, R(1e-4), &report));
    snprintf(detail, sizeof detail, "%u substeps of %g s", report.substeps,
             (double)report.substep_dt);
    expect_detail("steel: the 1e-4 s step's substeps fit the limit and the stable dt",
                  report.substeps >= 1 && report.substeps <= 1000 &&
                      (double)report.substep_dt <= (double)stable * (1.0 + 1e-4),
                  detail);
    diag_check("steel: diagnostics finite", h.w);
    host_free(&h);

    /* Raised limit: 1/600 s is accepted; the limit is exact. */
    hb = steel_world(4000);
    track(hb.w);
    ACCEPTED("steel: step of 1/600 s (limit 4000)", 1,
             mpm_world_step(hb.w, R(1.0 / 600.0), &report));
    s_needed = report.substeps;
    snprintf(detail, sizeof detail, "%u substeps", s_needed);
    expect_detail("steel: 1/600 s took between 1000 and 4000 substeps",
                  s_needed > 1000 && s_needed <= 4000, detail);
    diag_check("steel: diagnostics finite after 1/600 s", hb.w);
    host_free(&hb);
    hs = steel_world(s_needed - 1);
    track(hs.w);
    REFUSED("steel: step of 1/600 s with the limit one below what it needs",
            MPM_STATUS_SUBSTEP_LIMIT, mpm_world_step(hs.w, R(1.0 / 600.0), OUT(MpmStepReport)));
    host_free(&hs);
    hs = steel_world(s_needed);
    track(hs.w);
    ACCEPTED("steel: step of 1/600 s with the limit exactly what it needs", 1,
             mpm_world_step(hs.w, R(1.0 / 600.0), &report));
    expect_true("steel: the same substeps", report.substeps == s_needed);
    host_free(&hs);
}

/* A stiff block (E 1e8) at rest in the air, with or without a thermostat of gain 1e12 and
 * max_alpha 1e12. */
static Host thermostat_twin(int thermostat) {
    MpmWorldDef d = def_2d(256);
    Host h;
    MpmMaterialDef m = mpm_material_def_default();
    MpmIdRange ids;
    uint32_t id = 0;
    if (thermostat) {
        d.effects.damping.declared = 1;
        d.effects.damping.feedback.declared = 1;
        d.effects.damping.feedback.gain = R(1e12);
        d.effects.damping.feedback.max_alpha = R(1e12);
    }
    h = host_new("thermostat gain: setup", &d);
    m.youngs_modulus = R(1e8);
    if (mpm_world_add_material(h.w, &m, &id) != MPM_STATUS_OK ||
        mpm_world_fill_box(h.w, v3(0.3, 0.5, 0), v3(0.7, 0.7, 0), id, v3(0, 0, 0), &ids) !=
            MPM_STATUS_OK) {
        fail("thermostat gain: setup", "the material or the box was refused");
    }
    return h;
}

static void huge_gain(void) {
    Host hd = thermostat_twin(1), hp = thermostat_twin(0);
    MpmStepReport rd, rp;
    double alpha = -1.0, alpha_max = 0.0;
    int step, same = 1, ok = 1;
    char detail[256], name[96];
    unsigned first_d = 0, first_p = 0;

    track(hd.w);
    track(hp.w);
    for (step = 0; step < 6; step++) {
        MpmStatus sd = mpm_world_step(hd.w, R(1.0 / 200.0), &rd);
        MpmStatus sp = mpm_world_step(hp.w, R(1.0 / 200.0), &rp);
        snprintf(name, sizeof name, "thermostat gain 1e12: step %d", step + 1);
        if (sd != MPM_STATUS_OK) {
            status_fail(name, "the step with the thermostat was refused", sd);
        }
        if (sp != MPM_STATUS_OK) {
            status_fail(name, "the step without the thermostat was refused", sp);
        }
        if (mpm_world_feedback_alpha(hd.w, &alpha) != MPM_STATUS_OK) {
            fail(name, "feedback_alpha refused");
        }
        ok &= isfinite(alpha) && alpha >= 0.0 && alpha <= 1e12;
        alpha_max = alpha > alpha_max ? alpha : alpha_max;
        same &= rd.substeps == rp.substeps;
        if (step == 0) {
            first_d = rd.substeps;
            first_p = rp.substeps;
        }
        if (!same) {
            snprintf(detail, sizeof detail,
                     "step %d: %u substeps with the thermostat, %u without", step + 1,
                     rd.substeps, rp.substeps);
            fail(name, detail);
        }
    }
    rehash();
    snprintf(detail, sizeof detail,
             "%u substeps per step with and %u without (first step); largest alpha %g",
             first_d, first_p, alpha_max);
    expect_detail("thermostat gain 1e12: 6 steps accepted, each with the substeps of the scene "
                  "without the thermostat",
                  same, detail);
    expect_detail("thermostat gain 1e12: alpha finite and in [0, max_alpha] after each step", ok,
                  detail);
    expect_true("thermostat gain 1e12: the thermostat acted (alpha > 0)", alpha_max > 0.0);
    diag_check("thermostat gain 1e12: diagnostics finite", hd.w);
    active_check("thermostat gain 1e12: every active particle finite", hd.w);
    host_free(&hd);
    host_free(&hp);
}

/* Limits of the definition. */
static void limits(void) {
    const MpmWorldDef base = def_2d(64);
    MpmWorldDef d;
    MpmMemoryRequirements req, req_base;
    Block mem;
    MpmWorld *w = NULL;
    MpmWorldDef back;
    Host h;
    MpmStepReport report;

    expect_true("limits: defaults max_substeps 1000 and max_volume_ratio 100",
                base.max_substeps == 1000 && base.max_volume_ratio == R(100.0));
    if (mpm_memory_requirements(&base, &req_base) != MPM_STATUS_OK) {
        fail("limits: setup", "mpm_memory_requirements refused the base definition");
    }
    mem = block_new(req_base.bytes, req_base.align);

#define BAD_LIMIT(label, stmt)                                                                \
    d = base;                                                                                 \
    stmt;                                                                                     \
    REFUSED("limits: " label ": mpm_memory_requirements", MPM_STATUS_INVALID_LIMIT,           \
            mpm_memory_requirements(&d, OUT(MpmMemoryRequirements)));                         \
    memset(mem.raw, PATTERN, mem.raw_len);                                                    \
    REFUSED("limits: " label ": mpm_world_init", MPM_STATUS_INVALID_LIMIT,                    \
            mpm_world_init(&d, mem.at, req_base.bytes, OUT(MpmWorld *)));                      \
    if (!pattern_intact(mem.raw, mem.raw_len)) {                                              \
        fail("limits: " label, "the refused init wrote the memory");                          \
    }
    BAD_LIMIT("max_substeps 0", d.max_substeps = 0);
    BAD_LIMIT("max_substeps 1048577", d.max_substeps = 1048577u);
    BAD_LIMIT("max_substeps 0xFFFFFFFF", d.max_substeps = 0xFFFFFFFFu);
    BAD_LIMIT("max_volume_ratio 1", d.max_volume_ratio = R(1.0));
    BAD_LIMIT("max_volume_ratio 0.5", d.max_volume_ratio = R(0.5));
    BAD_LIMIT("max_volume_ratio 0", d.max_volume_ratio = R(0.0));
    BAD_LIMIT("max_volume_ratio -2", d.max_volume_ratio = R(-2.0));
    BAD_LIMIT("max_volume_ratio NaN", d.max_volume_ratio = R(NAN));
    BAD_LIMIT("max_volume_ratio -inf", d.max_volume_ratio = R(-INFINITY));
#undef BAD_LIMIT

#define GOOD_LIMIT(label, stmt)                                                               \
    d = base;                                                                                 \
    stmt;                                                                                     \
    ACCEPTED("limits: " label, 0, mpm_memory_requirements(&d, &req))
    GOOD_LIMIT("max_substeps 1", d.max_substeps = 1);
    GOOD_LIMIT("max_substeps 1048576", d.max_substeps = 1048576u);
    GOOD_LIMIT("max_volume_ratio +inf (no bound)", d.max_volume_ratio = R(INFINITY));
    GOOD_LIMIT("max_volume_ratio 1.001", d.max_volume_ratio = R(1.001));
#undef GOOD_LIMIT
    expect_true("limits: the limits take no memory", req.bytes == req_base.bytes);

    /* The limits read back. */
    d = base;
    d.max_substeps = 1048576u;
    d.max_volume_ratio = R(INFINITY);
    ACCEPTED("limits: init with max_substeps 1048576 and max_volume_ratio +inf", 0,
             mpm_world_init(&d, mem.at, req_base.bytes, &w));
    ACCEPTED("limits: get_def", 0, mpm_world_get_def(w, &back));
    expect_true("limits: the limits read back",
                back.max_substeps == 1048576u && isinf(back.max_volume_ratio) &&
                    back.max_volume_ratio > R(0.0));
    free(mem.raw);

    /* max_substeps 1: a step that needs 2 substeps is refused, one that needs 1 accepted. */
    d = base;
    d.max_substeps = 1;
    h = host_new("limits: max_substeps 1 setup", &d);
    track(h.w);
    {
        MpmMaterialDef m = mpm_material_def_default();
        MpmIdRange ids;
        uint32_t id = 0;
        mpm_real stable = R(0.0);
        ACCEPTED("limits: max_substeps 1: material", 1, mpm_world_add_material(h.w, &m, &id));
        ACCEPTED("limits: max_substeps 1: box", 1,
                 mpm_world_fill_box(h.w, v3(0.4, 0.4, 0), v3(0.5, 0.5, 0), id, v3(0, 0, 0),
                                    &ids));
        ACCEPTED("limits: max_substeps 1: stable_dt", 0, mpm_world_stable_dt(h.w, &stable));
        REFUSED("limits: max_substeps 1: step of 2.5 stable steps", MPM_STATUS_SUBSTEP_LIMIT,
                mpm_world_step(h.w, stable * R(2.5), OUT(MpmStepReport)));
        ACCEPTED("limits: max_substeps 1: step of half a stable step", 1,
                 mpm_world_step(h.w, stable * R(0.5), &report));
        expect_true("limits: max_substeps 1: one substep", report.substeps == 1);
    }
    host_free(&h);
}

int main(void) {
    Host hs;

    out_reset();
    g_also_intact = guards_intact;
    expect_true("abi version matches the header", mpm_abi_version() == MPM_GIMP_ABI_VERSION);

    new_status_strings();
    aliasing();
    not_a_world_at_page_end();
    thermostat_world();
    seeding_underflow();
    hs = state_world();
    state_edits(&hs);
    random_corruption(&hs);
    ACCEPTED("state: the original steps after the snapshot checks", 1,
             mpm_world_step(hs.w, R(1e-3), OUT(MpmStepReport)));
    diag_check("state: the original's diagnostics are finite", hs.w);
    host_free(&hs);
    runaway_run("runaway (max_volume_ratio 100)", R(100.0), 0.15, 3000, 0);
    runaway_run("runaway (max_volume_ratio 1.01)", R(1.01), 0.2, 500, 1);
    steel();
    huge_gain();
    limits();

    printf("all %lu hostile checks passed\n", g_checks);
    return 0;
}
