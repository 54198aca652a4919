/*
 * Values in range, from C: a snapshot that opens is a world that steps, hardening cannot run
 * away unnoticed, and every rate a world accepts is one a step resolves. Each section is the
 * reproducer of a defect a hostile pass over the C interface found, and fails without its fix:
 *   1. position_low: mpm_world_open refuses a snapshot whose low part of a position is NaN,
 *      infinite, 1e30, 0.25 m or four units in the last place of the position (it would have
 *      frozen the particle or moved it silently), and opens one within one unit, which steps
 *      with nothing frozen and the particle where the pair says it is;
 *   2. plastic history: open refuses snow with J_p <= 0 or a hardening whose wave speed no step
 *      above MPM_MIN_STABLE_DT resolves, a von Mises or Drucker-Prager history < 0, and a
 *      history on a model without one; it opens snow compacted within range and a positive
 *      plastic strain, and those step;
 *   3. snow's hardening: blocks of snow with xi = 10 and 100 dropped at 3 m/s, and 100 at
 *      10 m/s, on a stick floor for 300 frames: the kinetic energy never exceeds what the
 *      block started with (5 % for round-off), and a particle that froze is counted as
 *      runaway in the report; a hardening coefficient past MPM_MAX_HARDENING_COEFFICIENT is
 *      MPM_STATUS_INVALID_MATERIAL (xi = 1000 went from 738 J to 1e32 J with 190 particles
 *      active at up to 1e16 m/s before the fix);
 *   4. rates: a damping zone, a grid damping schedule, a viscosity or a wave speed that no
 *      step above MPM_MIN_STABLE_DT resolves is MPM_STATUS_STABLE_STEP_TOO_SHORT (a zone of
 *      FLT_MAX was accepted and stable_dt then returned a floor at which one step froze every
 *      particle), and so are a per-particle damping rate and a particle speed past their
 *      bounds; derived moduli that overflow are MPM_STATUS_INVALID_MATERIAL; a world whose
 *      rate is just inside its bound steps at stable_dt (>= MPM_MIN_STABLE_DT / 2) with
 *      nothing frozen;
 *   5. collider records: mpm_world_open refuses a snapshot whose collider record holds what
 *      mpm_world_add_collider could not have written: a position, velocity, radius or friction
 *      past mpm_real's range (in single precision: such a collider read back as infinities
 *      and touched nothing), a radius that rounds to 0 or is 0, a negative friction, a
 *      rotation not of unit length, a pose time other than the world's (NaN, later, earlier),
 *      in 2D a position or velocity z or a turn about x, an unknown contact or shape; the
 *      intact snapshot opens, steps and reads back its collider.
 * Every refused call changes no byte of the world (FNV-1a hash of its extent).
 *
 * One line per check ("ok <name>: ..."); the first failure prints "FAIL <name>: <why>" and
 * exits with status 1. The last line on success is "all <n> ranges checks passed".
 * tests/c_checks.rs builds this file with strict warnings and with AddressSanitizer and
 * UndefinedBehaviorSanitizer, and runs it. Works for both precisions (mpm_real, R()).
 */
#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mpm_gimp.h"

#ifdef MPM_GIMP_F64
#define REAL_MAX DBL_MAX
#define REAL_MIN DBL_MIN
#define NEXT_UP(x) nextafter((x), INFINITY)
#else
#define REAL_MAX FLT_MAX
#define REAL_MIN FLT_MIN
#define NEXT_UP(x) nextafterf((x), INFINITY)
#endif

#include "check.h"

/* ---- worlds in memory of their own ---------------------------------------------------- */

typedef struct {
    unsigned char *raw;
    MpmWorld *w;
    size_t bytes;
} Mem;

static unsigned char *aligned(unsigned char *raw, size_t align) {
    uintptr_t p = (uintptr_t)raw;
    return raw + ((align - p % align) % align);
}

/* A world of `d` in fresh memory; fails the check `name` if init refuses. */
static Mem world_new(const char *name, const MpmWorldDef *d) {
    Mem m;
    MpmMemoryRequirements req;
    MpmStatus s = mpm_memory_requirements(d, &req);
    if (s != MPM_STATUS_OK) {
        fail(name, mpm_status_string(s));
    }
    m.raw = (unsigned char *)malloc(req.bytes + req.align);
    if (m.raw == NULL) {
        fail(name, "out of memory");
    }
    memset(m.raw, 0, req.bytes + req.align);
    m.w = NULL;
    s = mpm_world_init(d, aligned(m.raw, req.align), req.bytes, &m.w);
    if (s != MPM_STATUS_OK) {
        fail(name, mpm_status_string(s));
    }
    m.bytes = req.bytes;
    return m;
}

/* A byte copy of `src` in memory of its own (not opened). */
static Mem copy_of(const Mem *src) {
    Mem m;
    m.raw = (unsigned char *)malloc(src->bytes + 64);
    if (m.raw == NULL) {
        fail("copy_of", "out of memory");
    }
    memcpy(aligned(m.raw, 64), src->w, src->bytes);
    m.w = (MpmWorld *)(void *)aligned(m.raw, 64);
    m.bytes = src->bytes;
    return m;
}

static void mem_free(Mem *m) {
    free(m->raw);
    m->raw = NULL;
    m->w = NULL;
}

/* The address in `copy` of the byte at `p` of the world `src`. */
static void *at_copy(const Mem *copy, const Mem *src, const void *p) {
    return (unsigned char *)(void *)copy->w +
           ((const unsigned char *)p - (const unsigned char *)(const void *)src->w);
}

static void ok_status(const char *name, MpmStatus s) {
    if (s != MPM_STATUS_OK) {
        char why[256];
        snprintf(why, sizeof why, "expected ok, got %u (%s)", (unsigned)s, mpm_status_string(s));
        fail(name, why);
    }
}

/* `call`'s status must be `want`, and the world `w` (of `bytes`) must be unchanged. */
static void refused(const char *name, MpmStatus want, MpmStatus got, const MpmWorld *w,
                    size_t bytes, uint64_t before) {
    char why[256];
    if (got != want) {
        snprintf(why, sizeof why, "expected %u (%s), got %u (%s)", (unsigned)want,
                 mpm_status_string(want), (unsigned)got, mpm_status_string(got));
        fail(name, why);
    }
    if (fnv1a(w, bytes) != before) {
        fail(name, "the refused call changed the world");
    }
    pass(name, got);
}

static MpmWorldDef def_2d(void) { return grid_2d(1024, 4); }

static MpmIdRange fill(const char *name, MpmWorld *w, uint32_t material, double x0, double y0,
                       double x1, double y1, double vy) {
    MpmIdRange ids;
    ok_status(name, mpm_world_fill_box(w, v3(x0, y0, 0.0), v3(x1, y1, 0.0), material,
                                       v3(0.0, vy, 0.0), &ids));
    if (ids.count == 0) {
        fail(name, "the fill added no particle");
    }
    return ids;
}

static MpmStepReport step(const char *name, MpmWorld *w, double dt) {
    MpmStepReport r;
    ok_status(name, mpm_world_step(w, R(dt), &r));
    return r;
}

/* Opens `copy` (a snapshot edited in place) and expects `want`; a refused open leaves its
 * bytes as they were. */
static void open_expect(const char *name, Mem *copy, MpmStatus want) {
    uint64_t before = fnv1a(copy->w, copy->bytes);
    MpmWorld *opened = NULL;
    MpmStatus s = mpm_world_open(copy->w, copy->bytes, &opened);
    if (want == MPM_STATUS_OK) {
        ok_status(name, s);
        pass(name, s);
    } else {
        refused(name, want, s, copy->w, copy->bytes, before);
    }
}

/* ---- 1. the low part of a position ------------------------------------------------------ */

static void position_low(void) {
    MpmWorldDef d = def_2d();
    MpmMaterialDef m = mpm_material_def_default();
    Mem src = world_new("low: world", &d);
    uint32_t id;
    MpmParticlesView v;
    mpm_real x, ulp;
    const double bad[4] = {1e30, 0.25, -0.25, 0.0};
    int k;
    ok_status("low: material", mpm_world_add_material(src.w, &m, &id));
    fill("low: fill", src.w, id, 0.3, 0.3, 0.6, 0.6, 0.0);
    step("low: first step", src.w, 1.0 / 240.0);
    ok_status("low: view", mpm_world_particles(src.w, &v));
    x = v.position[0][0];
    ulp = NEXT_UP((mpm_real)fabs((double)x)) - (mpm_real)fabs((double)x);
    /* NaN, infinities, far off, and four units in the last place. */
    for (k = 0; k < 7; k++) {
        char name[96];
        Mem c = copy_of(&src);
        mpm_real *low = (mpm_real *)at_copy(&c, &src, &v.position_low[0][0]);
        mpm_real value = k == 0 ? (mpm_real)NAN
                       : k == 1 ? (mpm_real)INFINITY
                       : k == 2 ? -(mpm_real)INFINITY
                       : k < 6  ? R(bad[k - 3])
                                : 4 * ulp;
        *low = value;
        snprintf(name, sizeof name, "low: position_low %g of a position %g refused",
                 (double)value, (double)x);
        open_expect(name, &c, MPM_STATUS_INVALID_STATE);
        mem_free(&c);
    }
    /* Within one unit in the last place: opens, steps, and the particle stays where it is
     * (at rest on nothing: it falls by g t^2 / 2 at most). */
    {
        Mem c = copy_of(&src);
        mpm_real *low = (mpm_real *)at_copy(&c, &src, &v.position_low[0][0]);
        MpmWorld *opened = NULL;
        MpmStepReport r;
        MpmParticlesView after;
        *low = ulp / 2;
        ok_status("low: half a unit opens", mpm_world_open(c.w, c.bytes, &opened));
        r = step("low: half a unit steps", opened, 1.0 / 240.0);
        ok_status("low: view after", mpm_world_particles(opened, &after));
        expect_true("low: half a unit steps with nothing frozen, x moved less than 1 mm",
                    r.frozen == 0 && fabs((double)after.position[0][0] - (double)x) < 1e-3);
        mem_free(&c);
    }
    mem_free(&src);
}

/* ---- 2. the plastic history ------------------------------------------------------------- */

static void plastic_history(void) {
    MpmWorldDef d = def_2d();
    MpmMaterialDef snow = mpm_material_def_default();
    MpmMaterialDef metal = mpm_material_def_default();
    MpmMaterialDef sand = mpm_material_def_default();
    MpmMaterialDef rubber = mpm_material_def_default();
    Mem src;
    uint32_t ids[4];
    MpmIdRange r[4];
    MpmParticlesView v;
    struct {
        int block;
        double value;
        int opens;
        const char *what;
    } edits[] = {
        {0, -1.0, 0, "snow J_p = 0"},
        {0, -2.0, 0, "snow J_p < 0"},
        {0, -1e4, 0, "snow hardened past any stable step"},
        {0, NAN, 0, "snow history NaN"},
        {0, -0.5, 1, "snow compacted to J_p = 0.5"},
        {0, 0.2, 1, "snow stretched to J_p = 1.2"},
        {1, -5.0, 0, "von Mises plastic strain -5"},
        {1, -1e-3, 0, "von Mises plastic strain -1e-3"},
        {1, 0.1, 1, "von Mises plastic strain 0.1"},
        {2, -1.0, 0, "Drucker-Prager plastic shear -1"},
        {2, 0.5, 1, "Drucker-Prager plastic shear 0.5"},
        {3, 0.3, 0, "neo-Hookean with a history"},
    };
    size_t k;
    d.effects.plasticity = 1;
    snow.model = MPM_MATERIAL_MODEL_SNOW;
    metal.model = MPM_MATERIAL_MODEL_VON_MISES;
    sand.model = MPM_MATERIAL_MODEL_DRUCKER_PRAGER;
    src = world_new("history: world", &d);
    ok_status("history: snow", mpm_world_add_material(src.w, &snow, &ids[0]));
    ok_status("history: metal", mpm_world_add_material(src.w, &metal, &ids[1]));
    ok_status("history: sand", mpm_world_add_material(src.w, &sand, &ids[2]));
    ok_status("history: rubber", mpm_world_add_material(src.w, &rubber, &ids[3]));
    r[0] = fill("history: fill", src.w, ids[0], 0.1, 0.1, 0.3, 0.3, 0.0);
    r[1] = fill("history: fill", src.w, ids[1], 0.4, 0.1, 0.6, 0.3, 0.0);
    r[2] = fill("history: fill", src.w, ids[2], 0.1, 0.5, 0.3, 0.7, 0.0);
    r[3] = fill("history: fill", src.w, ids[3], 0.5, 0.5, 0.7, 0.7, 0.0);
    step("history: first step", src.w, 1.0 / 240.0);
    ok_status("history: view", mpm_world_particles(src.w, &v));
    if (v.plastic == NULL) {
        fail("history: view", "no plastic column with plasticity declared");
    }
    for (k = 0; k < sizeof edits / sizeof edits[0]; k++) {
        char name[256];
        Mem c = copy_of(&src);
        mpm_real *p = (mpm_real *)at_copy(&c, &src, &v.plastic[r[edits[k].block].first]);
        *p = R(edits[k].value);
        snprintf(name, sizeof name, "history: %s %s", edits[k].what,
                 edits[k].opens ? "opens and steps" : "refused");
        if (edits[k].opens) {
            MpmWorld *opened = NULL;
            MpmStepReport rep;
            MpmDiagnostics diag;
            ok_status(name, mpm_world_open(c.w, c.bytes, &opened));
            rep = step(name, opened, 1.0 / 60.0);
            ok_status(name, mpm_world_diagnostics(opened, &diag));
            expect_true(name, rep.frozen == 0 && isfinite(diag.kinetic) && isfinite(diag.strain));
        } else {
            open_expect(name, &c, MPM_STATUS_INVALID_STATE);
        }
        mem_free(&c);
    }
    mem_free(&src);
}

/* ---- 3. snow's hardening ---------------------------------------------------------------- */

/* Snow with hardening coefficient `xi` dropped at `speed` on a stick floor for 300 frames of
 * 1/60 s (at the stable step where a frame would need more than max_substeps): the kinetic
 * energy never exceeds the energy the block started with above the floor (5 % for
 * round-off), and every particle that froze is counted as runaway. (The strain energy is not
 * bounded by it: compaction raises snow's moduli at a fixed elastic strain.) */
static void snow_drop(double xi, double speed) {
    char name[1024];
    MpmWorldDef d = def_2d();
    MpmMaterialDef snow = mpm_material_def_default();
    Mem m;
    uint32_t id;
    MpmDiagnostics diag;
    double e0, k_max = 0.0;
    unsigned frozen = 0, runaway = 0, substeps = 0;
    int frame;
    d.effects.plasticity = 1;
    d.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    snow.model = MPM_MATERIAL_MODEL_SNOW;
    snow.youngs_modulus = R(1.4e5);
    snow.density = R(400.0);
    snow.hardening_coefficient = R(xi);
    m = world_new("snow: world", &d);
    ok_status("snow: material", mpm_world_add_material(m.w, &snow, &id));
    fill("snow: fill", m.w, id, 0.3, 0.1, 0.65, 0.45, -speed);
    ok_status("snow: diagnostics", mpm_world_diagnostics(m.w, &diag));
    /* The potential is measured from y = 0; the floor (the admissible region's lower face)
     * is one cell up. */
    e0 = diag.kinetic + diag.strain + diag.potential - diag.mass * 9.81 * 0.05;
    for (frame = 0; frame < 300; frame++) {
        MpmStepReport r;
        mpm_real dt = R(1.0 / 60.0);
        MpmStatus s = mpm_world_step(m.w, dt, &r);
        if (s == MPM_STATUS_SUBSTEP_LIMIT) {
            ok_status("snow: stable dt", mpm_world_stable_dt(m.w, &dt));
            s = mpm_world_step(m.w, dt, &r);
        }
        snprintf(name, sizeof name, "snow xi %g at %g m/s: frame %d", xi, speed, frame);
        ok_status(name, s);
        substeps += r.substeps;
        frozen += r.frozen;
        runaway += r.runaway;
        if (r.runaway > r.frozen || ((r.flags & MPM_STEP_FLAG_RUNAWAY) != 0) != (r.runaway > 0)) {
            fail(name, "the report's runaway count disagrees with its frozen count or flags");
        }
        ok_status(name, mpm_world_diagnostics(m.w, &diag));
        if (!(diag.kinetic <= 1.05 * e0)) {
            char why[160];
            snprintf(why, sizeof why, "kinetic energy %g J above the start's %g J", diag.kinetic,
                     e0);
            fail(name, why);
        }
        k_max = diag.kinetic > k_max ? diag.kinetic : k_max;
    }
    snprintf(name, sizeof name,
             "snow xi %g at %g m/s: 300 frames in %u substeps, kinetic energy %.3g J at most "
             "(%.1f J to start), %u frozen, all of them runaway",
             xi, speed, substeps, k_max, e0, frozen);
    expect_true(name, frozen == runaway);
    mem_free(&m);
}

/* Past MPM_MAX_HARDENING_COEFFICIENT the model gains energy without bound (xi = 1000 went from
 * 738 J to 1e32 J): refused. */
static void snow_bound(void) {
    MpmWorldDef d = def_2d();
    MpmMaterialDef snow = mpm_material_def_default();
    Mem m;
    uint32_t id;
    uint64_t before;
    double xis[2] = {MPM_MAX_HARDENING_COEFFICIENT * 1.01, 1000.0};
    int k;
    d.effects.plasticity = 1;
    snow.model = MPM_MATERIAL_MODEL_SNOW;
    m = world_new("snow bound: world", &d);
    before = fnv1a(m.w, m.bytes);
    for (k = 0; k < 2; k++) {
        char name[96];
        snow.hardening_coefficient = R(xis[k]);
        snprintf(name, sizeof name, "snow: hardening coefficient %g refused", xis[k]);
        refused(name, MPM_STATUS_INVALID_MATERIAL, mpm_world_add_material(m.w, &snow, &id), m.w,
                m.bytes, before);
    }
    snow.hardening_coefficient = R(MPM_MAX_HARDENING_COEFFICIENT);
    ok_status("snow: hardening coefficient at the bound", mpm_world_add_material(m.w, &snow, &id));
    pass("snow: hardening coefficient at the bound accepted", MPM_STATUS_OK);
    mem_free(&m);
}

/* ---- 4. rates a step resolves ----------------------------------------------------------- */

static void rates(void) {
    const double floor_dt = MPM_MIN_STABLE_DT;
    MpmWorldDef base = def_2d();
    double rate_limit = (double)base.cfl / floor_dt;
    double speed_limit = (double)base.cfl * (double)base.cell_size / floor_dt;
    MpmMemoryRequirements req;
    MpmStatus s;
    /* Damping of the definition: a zone of the largest real, a zone and a schedule past the
     * bound, are refused by mpm_memory_requirements and mpm_world_init alike. */
    {
        int k;
        for (k = 0; k < 3; k++) {
            MpmWorldDef d = base;
            unsigned char *raw = (unsigned char *)malloc(1 << 20);
            MpmWorld *w = NULL;
            char name[128];
            d.effects.damping.declared = 1;
            if (k < 2) {
                d.effects.damping.zone_count = 1;
                d.effects.damping.zones[0].min = v3(0.0, 0.0, 0.0);
                d.effects.damping.zones[0].max = v3(1.0, 0.2, 0.0);
                d.effects.damping.zones[0].rate = k == 0 ? REAL_MAX : R(2.0 * rate_limit);
            } else {
                d.effects.damping.grid.points = 1;
                d.effects.damping.grid.values[0] = R(1.5 * rate_limit);
            }
            snprintf(name, sizeof name, "rates: %s refused by memory_requirements",
                     k == 0 ? "zone of the largest real" : k == 1 ? "zone past the bound"
                                                                  : "grid schedule past the bound");
            s = mpm_memory_requirements(&d, &req);
            if (s != MPM_STATUS_STABLE_STEP_TOO_SHORT) {
                fail(name, mpm_status_string(s));
            }
            pass(name, s);
            memset(raw, 0x5a, 1 << 20);
            s = mpm_world_init(&d, aligned(raw, 64), (1 << 20) - 64, &w);
            snprintf(name, sizeof name, "rates: and by world_init, the memory untouched");
            {
                size_t i;
                int touched = 0;
                for (i = 0; i < (1 << 20); i++) {
                    touched |= raw[i] != 0x5a;
                }
                expect_true(name, s == MPM_STATUS_STABLE_STEP_TOO_SHORT && !touched && w == NULL);
            }
            free(raw);
        }
    }
    /* A world with damping just inside the bound: it steps at its stable step, which is at
     * least half the floor, with nothing frozen; per-particle rates past their share are
     * refused. */
    {
        MpmWorldDef d = base;
        MpmMaterialDef m = mpm_material_def_default();
        Mem w;
        uint32_t id;
        MpmIdRange ids;
        mpm_real dt;
        MpmStepReport r;
        uint64_t before;
        mpm_real *too_much;
        size_t i;
        d.effects.damping.declared = 1;
        d.effects.damping.per_particle = 1;
        d.effects.damping.zone_count = 1;
        d.effects.damping.zones[0].min = v3(0.0, 0.0, 0.0);
        d.effects.damping.zones[0].max = v3(1.0, 1.0, 0.0);
        d.effects.damping.zones[0].rate = R(0.9 * rate_limit);
        w = world_new("rates: near the bound", &d);
        ok_status("rates: material", mpm_world_add_material(w.w, &m, &id));
        ids = fill("rates: fill", w.w, id, 0.3, 0.3, 0.6, 0.6, 0.0);
        ok_status("rates: stable dt", mpm_world_stable_dt(w.w, &dt));
        r = step("rates: step at stable dt", w.w, (double)dt);
        expect_true("rates: a zone at 0.9 of the bound steps at stable dt >= floor / 2, "
                    "nothing frozen",
                    (double)dt >= floor_dt / 2 && r.frozen == 0 && r.substeps == 1);
        r = step("rates: a tenth of it", w.w, (double)dt / 10.0);
        expect_true("rates: and at a tenth of it, nothing frozen", r.frozen == 0);
        too_much = (mpm_real *)malloc(ids.count * sizeof(mpm_real));
        for (i = 0; i < ids.count; i++) {
            too_much[i] = R(0.1 * rate_limit);
        }
        before = fnv1a(w.w, w.bytes);
        s = mpm_world_set_particle_damping(w.w, ids.first, too_much, too_much, ids.count);
        refused("rates: per-particle damping past its share refused", MPM_STATUS_STABLE_STEP_TOO_SHORT,
                s, w.w, w.bytes, before);
        for (i = 0; i < ids.count; i++) {
            too_much[i] = R(0.04 * rate_limit);
        }
        ok_status("rates: per-particle damping within its share",
                  mpm_world_set_particle_damping(w.w, ids.first, too_much, too_much, ids.count));
        ok_status("rates: stable dt with per-particle damping", mpm_world_stable_dt(w.w, &dt));
        r = step("rates: step with per-particle damping", w.w, (double)dt);
        expect_true("rates: per-particle damping within its share steps at stable dt, nothing "
                    "frozen",
                    (double)dt >= floor_dt / 2 && r.frozen == 0);
        free(too_much);
        mem_free(&w);
    }
    /* Materials: a viscosity of the largest real, a viscosity and a wave speed past their
     * bounds are refused as too fast for any step; Young's modulus at the largest real and a
     * density at the smallest (derived moduli that overflow) are invalid materials. */
    {
        MpmWorldDef d = base;
        Mem w = world_new("rates: materials", &d);
        MpmMaterialDef m;
        uint32_t id;
        uint64_t before = fnv1a(w.w, w.bytes);
        double kinematic_limit = (double)d.cfl * (double)d.cell_size * (double)d.cell_size /
                                 (4.0 * floor_dt);
        m = mpm_material_def_default();
        m.viscosity = REAL_MAX;
        refused("rates: viscosity of the largest real refused", MPM_STATUS_STABLE_STEP_TOO_SHORT,
                mpm_world_add_material(w.w, &m, &id), w.w, w.bytes, before);
        m = mpm_material_def_default();
        m.viscosity = R(2.0 * kinematic_limit * (double)m.density);
        refused("rates: viscosity past the bound refused", MPM_STATUS_STABLE_STEP_TOO_SHORT,
                mpm_world_add_material(w.w, &m, &id), w.w, w.bytes, before);
        m = mpm_material_def_default();
        /* c = sqrt(E (1 - nu) / ((1 + nu)(1 - 2 nu) rho)): E = 4 rho c^2 puts c past the bound. */
        m.youngs_modulus = R(4.0 * (double)m.density * speed_limit * speed_limit);
        if (isfinite((double)m.youngs_modulus)) {
            refused("rates: wave speed past the bound refused", MPM_STATUS_STABLE_STEP_TOO_SHORT,
                    mpm_world_add_material(w.w, &m, &id), w.w, w.bytes, before);
        }
        m = mpm_material_def_default();
        m.youngs_modulus = REAL_MAX;
        refused("rates: Young's modulus of the largest real: derived moduli overflow",
                MPM_STATUS_INVALID_MATERIAL, mpm_world_add_material(w.w, &m, &id), w.w, w.bytes,
                before);
        m = mpm_material_def_default();
        m.density = REAL_MIN;
        s = mpm_world_add_material(w.w, &m, &id);
        if (s == MPM_STATUS_INVALID_MATERIAL || s == MPM_STATUS_STABLE_STEP_TOO_SHORT) {
            refused("rates: density of the smallest real refused", s, s, w.w, w.bytes, before);
        } else {
            fail("rates: density of the smallest real refused", mpm_status_string(s));
        }
        /* A particle speed past the bound, added or filled. */
        m = mpm_material_def_default();
        ok_status("rates: a material", mpm_world_add_material(w.w, &m, &id));
        before = fnv1a(w.w, w.bytes);
        {
            MpmIdRange ids;
            mpm_real fast = R(2.0 * speed_limit);
            refused("rates: a fill faster than any resolved speed refused",
                    MPM_STATUS_STABLE_STEP_TOO_SHORT,
                    mpm_world_fill_box(w.w, v3(0.3, 0.3, 0.0), v3(0.5, 0.5, 0.0), id,
                                       v3((double)fast, 0.0, 0.0), &ids),
                    w.w, w.bytes, before);
        }
        mem_free(&w);
    }
}

/* ---- 5. collider records ----------------------------------------------------------------- */

/* A collider's record in a world's buffer: 8-byte fields (uint64 or double), in this order:
 * shape, contact, friction, size[3], position[3], rotation[4], velocity[3],
 * angular_velocity[3], pose_time, a distance field's grid[4]. */
enum {
    F_SHAPE = 0,
    F_CONTACT = 1,
    F_FRICTION = 2,
    F_SIZE = 3,
    F_POSITION = 6,
    F_ROTATION = 9,
    F_VELOCITY = 13,
    F_ANGULAR = 16,
    F_POSE_TIME = 19,
    RECORD_FIELDS = 24
};

/* The record in `w` (of `bytes`) that starts with a sphere's shape, slip contact and a
 * friction of 0.375, or NULL. */
static unsigned char *sphere_record(const MpmWorld *w, size_t bytes) {
    unsigned char head[24];
    const unsigned char *at = (const unsigned char *)(const void *)w;
    uint64_t shape = MPM_COLLIDER_SHAPE_SPHERE, contact = MPM_CONTACT_SLIP;
    double friction = 0.375;
    size_t k;
    memcpy(head, &shape, 8);
    memcpy(head + 8, &contact, 8);
    memcpy(head + 16, &friction, 8);
    for (k = 0; k + 8 * RECORD_FIELDS <= bytes; k += 8) {
        if (memcmp(at + k, head, sizeof head) == 0) {
            return (unsigned char *)(void *)w + k;
        }
    }
    return NULL;
}

static void collider_records(void) {
    MpmWorldDef d = def_2d();
    MpmMaterialDef m = mpm_material_def_default();
    MpmColliderDef c = mpm_collider_def_default();
    MpmColliderState state;
    Mem src;
    uint32_t id, cid;
    double time;
    unsigned char *record;
    const int single = sizeof(mpm_real) == 4;
    /* Past mpm_real's range: infinite in double precision. */
    const double beyond = single ? 1e39 : (double)INFINITY;
    struct {
        const char *what;
        int field; /* of the record */
        int is_u64;
        double value;
        uint64_t code;
        int single_only; /* a value double precision holds */
    } edits[] = {
        {"position x past the real range", F_POSITION, 0, 0, 0, 0},
        {"position y NaN", F_POSITION + 1, 0, 0, 0, 0},
        {"2D: position z 0.5", F_POSITION + 2, 0, 0.5, 0, 0},
        {"velocity x past the real range", F_VELOCITY, 0, 0, 0, 0},
        {"2D: velocity z 1", F_VELOCITY + 2, 0, 1.0, 0, 0},
        {"2D: a turn about x", F_ANGULAR, 0, 1.0, 0, 0},
        {"radius past the real range", F_SIZE, 0, 0, 0, 0},
        {"radius 0", F_SIZE, 0, 0.0, 0, 0},
        {"radius 1e-300 (0 as a float)", F_SIZE, 0, 1e-300, 0, 1},
        {"friction -0.25", F_FRICTION, 0, -0.25, 0, 0},
        {"friction past the real range", F_FRICTION, 0, 0, 0, 0},
        {"rotation of length 2", F_ROTATION + 3, 0, 2.0, 0, 0},
        {"pose time NaN", F_POSE_TIME, 0, 0, 0, 0},
        {"pose time after the world's", F_POSE_TIME, 0, 0, 0, 0},
        {"pose time before the world's", F_POSE_TIME, 0, 0, 0, 0},
        {"contact 3", F_CONTACT, 1, 0, 3, 0},
        {"shape 9", F_SHAPE, 1, 0, 9, 0},
    };
    size_t e, n = sizeof edits / sizeof edits[0];
    d.effects.collider_capacity = 1;
    src = world_new("colliders: world", &d);
    ok_status("colliders: material", mpm_world_add_material(src.w, &m, &id));
    fill("colliders: fill", src.w, id, 0.3, 0.3, 0.6, 0.6, 0.0);
    c.shape = MPM_COLLIDER_SHAPE_SPHERE;
    c.contact = MPM_CONTACT_SLIP;
    c.friction = R(0.375);
    c.radius = R(0.1);
    c.position = v3(0.45, 0.7, 0.0);
    c.velocity = v3(0.2, -0.3, 0.0);
    c.angular_velocity = v3(0.0, 0.0, 2.0);
    ok_status("colliders: a sphere", mpm_world_add_collider(src.w, &c, &cid));
    step("colliders: first step", src.w, 1.0 / 240.0);
    step("colliders: second step", src.w, 1.0 / 240.0);
    record = sphere_record(src.w, src.bytes);
    expect_true("colliders: the sphere's record is found in the snapshot", record != NULL);
    memcpy(&time, record + 8 * F_POSE_TIME, 8);
    expect_true("colliders: the record is posed at the world's time (2 steps of 1/240 s)",
                time == 2.0 * (double)R(1.0 / 240.0));
    edits[0].value = beyond;
    edits[1].value = (double)NAN;
    edits[3].value = beyond;
    edits[6].value = beyond;
    edits[10].value = beyond;
    edits[12].value = (double)NAN;
    edits[13].value = time + 1.0;
    edits[14].value = time - 1.0;
    for (e = 0; e < n; e++) {
        char name[128];
        Mem copy;
        unsigned char *field;
        if (edits[e].single_only && !single) {
            continue;
        }
        copy = copy_of(&src);
        field = (unsigned char *)at_copy(&copy, &src, record + 8 * edits[e].field);
        if (edits[e].is_u64) {
            memcpy(field, &edits[e].code, 8);
        } else {
            memcpy(field, &edits[e].value, 8);
        }
        snprintf(name, sizeof name, "colliders: a record with %s refused", edits[e].what);
        open_expect(name, &copy, MPM_STATUS_INVALID_STATE);
        mem_free(&copy);
    }
    {
        Mem copy = copy_of(&src);
        MpmWorld *opened = NULL;
        ok_status("colliders: the intact snapshot opens", mpm_world_open(copy.w, copy.bytes, &opened));
        step("colliders: the intact snapshot steps", opened, 1.0 / 240.0);
        ok_status("colliders: read back", mpm_world_get_collider(opened, cid, &state));
        expect_true("colliders: the intact snapshot's sphere reads back finite, in the plane",
                    isfinite((double)state.def.position.x) && state.def.position.z == 0 &&
                        state.def.radius == R(0.1));
        mem_free(&copy);
    }
    mem_free(&src);
}

int main(void) {
    position_low();
    plastic_history();
    snow_drop(10.0, 3.0);
    snow_drop(100.0, 3.0);
    snow_drop(100.0, 10.0);
    snow_bound();
    rates();
    collider_records();
    printf("all %lu ranges checks passed\n", g_checks);
    return 0;
}
