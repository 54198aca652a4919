/*
 * A particle's whole state through the C interface (MpmParticleState): what a host that moves
 * particles between worlds relies on.
 *   1. round trip: in each dimension form (plane strain: Drucker-Prager sand under cpGIMP;
 *      axisymmetric: von Mises metal under uGIMP; 3D: snow under the quadratic B-spline), with
 *      APIC, MUSL, plasticity, particle forces, per-particle damping, heat and diffusion with
 *      sources declared, a block thrown at a stick floor for 12 frames has its particles from a
 *      third of the way on copied out of the view into host arrays, removed, and added back
 *      with mpm_world_add_particles_with_state in two calls: every column of the view,
 *      the diagnostics and the stable step then equal those of its twin (a snapshot taken
 *      before, opened), byte for byte, and so they do 8 frames on; a third of the particles
 *      set in place to another third's state and back (mpm_world_set_particle_state) leave it
 *      equal to the twin again;
 *   2. migration: every particle moved, in three calls, into another world of the same
 *      definition and materials (stepped as many frames empty) steps 8 frames to the same
 *      bytes;
 *   3. misuse: NULL world, state, output and required arrays, an output or array inside the
 *      world, particles that do not exist, more than the capacity (refused before any array is
 *      read), an undeclared effect's array, a group given in part, and a value no world holds
 *      in each kind of column (each as mpm_world_open refuses it in a snapshot) are refused
 *      with their status, change no world's bytes and write no output; arrays the dimension
 *      does not read are not read.
 *
 * One line per check ("ok <name>: ..."); the first failure prints "FAIL <name>: <why>" and
 * exits with status 1. The last line on success is "all <n> state checks passed".
 * tests/c_checks.rs builds this file with strict warnings and with AddressSanitizer and
 * UndefinedBehaviorSanitizer, and runs it. Works for both precisions (mpm_real, R()).
 */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mpm_gimp.h"

#ifdef MPM_GIMP_F64
#define NEXT_UP(x) nextafter((x), INFINITY)
#else
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

static void ok_status(const char *name, MpmStatus s) {
    if (s != MPM_STATUS_OK) {
        char why[256];
        snprintf(why, sizeof why, "expected ok, got %u (%s)", (unsigned)s, mpm_status_string(s));
        fail(name, why);
    }
}

/* A world of `d` in fresh memory. */
static Mem world_new(const char *name, const MpmWorldDef *d) {
    Mem m;
    MpmMemoryRequirements req;
    ok_status(name, mpm_memory_requirements(d, &req));
    m.raw = (unsigned char *)calloc(1, req.bytes + req.align);
    if (m.raw == NULL) {
        fail(name, "out of memory");
    }
    m.w = NULL;
    ok_status(name, mpm_world_init(d, aligned(m.raw, req.align), req.bytes, &m.w));
    m.bytes = req.bytes;
    return m;
}

/* A byte copy of `src`, opened (its state checked). */
static Mem twin_of(const char *name, const Mem *src) {
    Mem m;
    MpmWorld *opened = NULL;
    m.raw = (unsigned char *)calloc(1, src->bytes + 64);
    if (m.raw == NULL) {
        fail(name, "out of memory");
    }
    memcpy(aligned(m.raw, 64), src->w, src->bytes);
    ok_status(name, mpm_world_open(aligned(m.raw, 64), src->bytes, &opened));
    m.w = opened;
    m.bytes = src->bytes;
    return m;
}

static void mem_free(Mem *m) {
    free(m->raw);
    m->raw = NULL;
    m->w = NULL;
}

/* ---- the scenes ------------------------------------------------------------------------ */

#define FRAME (1.0 / 240.0)

/* The scene of dimension form `dim` (0 plane strain, 1 axisymmetric, 2 3D). */
static MpmWorldDef scene_def(int dim) {
    MpmWorldDef d = mpm_world_def_default();
    int cells = dim == 2 ? 12 : 24;
    double h = 1.0 / cells;
    int f;
    d.dimension = dim == 0 ? MPM_DIMENSION_PLANE2D
                : dim == 1 ? MPM_DIMENSION_AXISYMMETRIC2D
                           : MPM_DIMENSION_SPACE3D;
    d.shape = dim == 0 ? MPM_SHAPE_CP_GIMP : dim == 1 ? MPM_SHAPE_GIMP : MPM_SHAPE_QUADRATIC_BSPLINE;
    d.cells[0] = (uint32_t)cells;
    d.cells[1] = (uint32_t)cells;
    d.cells[2] = dim == 2 ? (uint32_t)cells : 1;
    d.cell_size = R(h);
    if (dim == 1) {
        d.origin = v3(-h, 0.0, 0.0); /* the axis on the lower r face's wall plane */
    }
    d.transfer = MPM_TRANSFER_APIC;
    d.gravity = v3(0.0, -9.81, 0.0);
    for (f = 0; f < 6; f++) {
        d.faces[f] = MPM_BOUNDARY_SLIP;
    }
    d.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    d.particle_capacity = 1024;
    d.material_capacity = 2;
    d.effects.damping.declared = 1;
    d.effects.damping.per_particle = 1;
    d.effects.particle_forces = 1;
    d.effects.heat.declared = 1;
    d.effects.heat.sources = 1;
    d.effects.diffusion.declared = 1;
    d.effects.diffusion.sources = 1;
    d.effects.plasticity = 1;
    return d;
}

static MpmMaterialDef scene_material(int dim) {
    MpmMaterialDef m = mpm_material_def_default();
    m.model = dim == 0 ? MPM_MATERIAL_MODEL_DRUCKER_PRAGER
            : dim == 1 ? MPM_MATERIAL_MODEL_VON_MISES
                       : MPM_MATERIAL_MODEL_SNOW;
    m.viscosity = R(2.0);
    m.conductivity = R(1.0);
    m.diffusivity = R(1.0e-4);
    m.thermal_expansion = R(1.0e-4);
    m.reference_temperature = R(300.0);
    m.swelling = R(1.0e-2);
    return m;
}

static void materials(const char *name, MpmWorld *w, int dim) {
    MpmMaterialDef m = scene_material(dim), other = mpm_material_def_default();
    uint32_t id;
    ok_status(name, mpm_world_add_material(w, &m, &id));
    ok_status(name, mpm_world_add_material(w, &other, &id));
}

/* A block thrown at the floor, with per-particle forces, damping, temperatures,
 * concentrations and sources, and particle 3 frozen. */
static Mem scene(int dim) {
    MpmWorldDef d = scene_def(dim);
    Mem m = world_new("scene: world", &d);
    MpmIdRange ids;
    MpmParticleState frozen;
    const uint32_t frozen_status = MPM_PARTICLE_STATUS_FROZEN;
    mpm_real *v[9];
    size_t n, i;
    int k;
    materials("scene: materials", m.w, dim);
    if (dim == 2) {
        ok_status("scene: fill", mpm_world_fill_box(m.w, v3(0.3, 0.2, 0.3), v3(0.55, 0.45, 0.55),
                                                    0, v3(0.4, -2.0, 0.3), &ids));
    } else {
        ok_status("scene: fill", mpm_world_fill_box(m.w, v3(0.1, 0.1, 0.0), v3(0.4, 0.4, 0.0), 0,
                                                    v3(0.4, -2.0, 0.0), &ids));
    }
    n = ids.count;
    for (k = 0; k < 9; k++) {
        v[k] = (mpm_real *)malloc(n * sizeof(mpm_real));
        if (v[k] == NULL) {
            fail("scene", "out of memory");
        }
    }
    for (i = 0; i < n; i++) {
        v[0][i] = R(1.0e-3 * (double)(i % 5));
        v[1][i] = R(-2.0e-3 * (double)(i % 3));
        v[2][i] = R(1.0e-3 * (double)(i % 2));
        v[3][i] = R(0.5 * (double)(i % 4));
        v[4][i] = R(0.1 * (double)(i % 3));
        v[5][i] = R(300.0 + (double)(i % 7));
        v[6][i] = R(0.1 * (double)(i % 3));
        v[7][i] = R(1.0e5 * (double)(i % 2));
        v[8][i] = R(0.5 * (double)(i % 3));
    }
    ok_status("scene: forces", mpm_world_set_particle_forces(m.w, 0, v[0], v[1], v[2], n));
    ok_status("scene: damping", mpm_world_set_particle_damping(m.w, 0, v[3], v[4], n));
    ok_status("scene: temperature",
              mpm_world_set_particle_scalar(m.w, MPM_SCALAR_FIELD_TEMPERATURE, 0, v[5], n));
    ok_status("scene: concentration",
              mpm_world_set_particle_scalar(m.w, MPM_SCALAR_FIELD_CONCENTRATION, 0, v[6], n));
    ok_status("scene: heat sources",
              mpm_world_set_particle_sources(m.w, MPM_SCALAR_FIELD_TEMPERATURE, 0, v[7], n));
    ok_status("scene: concentration sources",
              mpm_world_set_particle_sources(m.w, MPM_SCALAR_FIELD_CONCENTRATION, 0, v[8], n));
    for (k = 0; k < 9; k++) {
        free(v[k]);
    }
    memset(&frozen, 0, sizeof frozen);
    frozen.status = &frozen_status;
    ok_status("scene: particle 3 frozen", mpm_world_set_particle_state(m.w, 3, &frozen, 1));
    return m;
}

static void frames(const char *name, MpmWorld *w, int count) {
    int f;
    for (f = 0; f < count; f++) {
        MpmStepReport r;
        ok_status(name, mpm_world_step(w, R(FRAME), &r));
        if (r.frozen != 0) {
            fail(name, "a particle froze");
        }
    }
}

/* ---- columns ----------------------------------------------------------------------------- */

#define REAL_COLUMNS 48

/* The view's Real columns, in the order of `state_fields`. */
static void view_columns(const MpmParticlesView *v, const mpm_real *c[REAL_COLUMNS]) {
    int k = 0, a;
    for (a = 0; a < 3; a++) c[k++] = v->position[a];
    for (a = 0; a < 3; a++) c[k++] = v->position_low[a];
    for (a = 0; a < 3; a++) c[k++] = v->velocity[a];
    c[k++] = v->mass;
    c[k++] = v->volume0;
    for (a = 0; a < 9; a++) c[k++] = v->displacement_gradient[a];
    for (a = 0; a < 6; a++) c[k++] = v->stress[a];
    for (a = 0; a < 3; a++) c[k++] = v->force[a];
    for (a = 0; a < 2; a++) c[k++] = v->damping[a];
    for (a = 0; a < 9; a++) c[k++] = v->affine[a];
    c[k++] = v->temperature;
    c[k++] = v->concentration;
    c[k++] = v->grid_temperature;
    c[k++] = v->grid_concentration;
    c[k++] = v->hoop;
    c[k++] = v->plastic;
    c[k++] = v->temperature_source;
    c[k++] = v->concentration_source;
}

/* The fields of a state, in the order of `view_columns`. */
static void state_fields(MpmParticleState *s, const mpm_real **f[REAL_COLUMNS]) {
    int k = 0, a;
    for (a = 0; a < 3; a++) f[k++] = &s->position[a];
    for (a = 0; a < 3; a++) f[k++] = &s->position_low[a];
    for (a = 0; a < 3; a++) f[k++] = &s->velocity[a];
    f[k++] = &s->mass;
    f[k++] = &s->volume0;
    for (a = 0; a < 9; a++) f[k++] = &s->displacement_gradient[a];
    for (a = 0; a < 6; a++) f[k++] = &s->stress[a];
    for (a = 0; a < 3; a++) f[k++] = &s->force[a];
    for (a = 0; a < 2; a++) f[k++] = &s->damping[a];
    for (a = 0; a < 9; a++) f[k++] = &s->affine[a];
    f[k++] = &s->temperature;
    f[k++] = &s->concentration;
    f[k++] = &s->grid_temperature;
    f[k++] = &s->grid_concentration;
    f[k++] = &s->hoop;
    f[k++] = &s->plastic;
    f[k++] = &s->temperature_source;
    f[k++] = &s->concentration_source;
}

/* Indices of columns in the order of `view_columns`. */
#define COL_VELOCITY 6
#define COL_MASS 9
#define COL_H 11
#define COL_STRESS 20
#define COL_DAMPING 29
#define COL_TEMPERATURE 40
#define COL_PLASTIC 45
#define COL_POSITION_LOW 3

/* Some particles' columns copied into the host's memory (NULL where the view has none). */
typedef struct {
    size_t count;
    mpm_real *real[REAL_COLUMNS];
    uint32_t *material;
    uint32_t *status;
} Rows;

static Rows rows_copy(const MpmWorld *w, size_t first, size_t count) {
    MpmParticlesView v;
    const mpm_real *c[REAL_COLUMNS];
    Rows r;
    int k;
    ok_status("rows: view", mpm_world_particles(w, &v));
    if (first + count > v.count) {
        fail("rows", "past the particles");
    }
    view_columns(&v, c);
    r.count = count;
    for (k = 0; k < REAL_COLUMNS; k++) {
        r.real[k] = NULL;
        if (c[k] != NULL) {
            r.real[k] = (mpm_real *)malloc(count * sizeof(mpm_real) + 1);
            if (r.real[k] == NULL) {
                fail("rows", "out of memory");
            }
            memcpy(r.real[k], c[k] + first, count * sizeof(mpm_real));
        }
    }
    r.material = (uint32_t *)malloc(count * sizeof(uint32_t) + 1);
    r.status = (uint32_t *)malloc(count * sizeof(uint32_t) + 1);
    if (r.material == NULL || r.status == NULL) {
        fail("rows", "out of memory");
    }
    memcpy(r.material, v.material + first, count * sizeof(uint32_t));
    memcpy(r.status, v.status + first, count * sizeof(uint32_t));
    return r;
}

static void rows_free(Rows *r) {
    int k;
    for (k = 0; k < REAL_COLUMNS; k++) {
        free(r->real[k]);
    }
    free(r->material);
    free(r->status);
}

/* The state of rows `from ..` of `r` (every column the rows have). */
static MpmParticleState rows_state(const Rows *r, size_t from) {
    MpmParticleState s;
    const mpm_real **f[REAL_COLUMNS];
    int k;
    memset(&s, 0, sizeof s);
    state_fields(&s, f);
    for (k = 0; k < REAL_COLUMNS; k++) {
        *f[k] = r->real[k] != NULL ? r->real[k] + from : NULL;
    }
    s.material = r->material + from;
    s.status = r->status + from;
    return s;
}

static int any_nonzero(const mpm_real *c, size_t n) {
    size_t i;
    for (i = 0; c != NULL && i < n; i++) {
        if (c[i] != 0) {
            return 1;
        }
    }
    return 0;
}

/* Fails `name` unless the particles of `a` and `b` are the same to the byte: every column of
 * their views, their diagnostics and their stable steps. */
static void expect_same(const char *name, const MpmWorld *a, const MpmWorld *b) {
    MpmParticlesView va, vb;
    const mpm_real *ca[REAL_COLUMNS], *cb[REAL_COLUMNS];
    MpmDiagnostics da, db;
    mpm_real sa, sb;
    int k, same = 1;
    ok_status(name, mpm_world_particles(a, &va));
    ok_status(name, mpm_world_particles(b, &vb));
    if (va.count != vb.count) {
        fail(name, "particle counts differ");
    }
    view_columns(&va, ca);
    view_columns(&vb, cb);
    for (k = 0; k < REAL_COLUMNS; k++) {
        if ((ca[k] == NULL) != (cb[k] == NULL)) {
            same = 0;
        } else if (ca[k] != NULL && memcmp(ca[k], cb[k], va.count * sizeof(mpm_real)) != 0) {
            char why[64];
            snprintf(why, sizeof why, "column %d differs", k);
            fail(name, why);
        }
    }
    same = same && memcmp(va.material, vb.material, va.count * sizeof(uint32_t)) == 0;
    same = same && memcmp(va.status, vb.status, va.count * sizeof(uint32_t)) == 0;
    ok_status(name, mpm_world_diagnostics(a, &da));
    ok_status(name, mpm_world_diagnostics(b, &db));
    ok_status(name, mpm_world_stable_dt(a, &sa));
    ok_status(name, mpm_world_stable_dt(b, &sb));
    same = same && memcmp(&da, &db, sizeof da) == 0 && memcmp(&sa, &sb, sizeof sa) == 0;
    expect_true(name, same);
}

/* ---- 1 and 2: round trip and migration ------------------------------------------------- */

static const char *const FORMS[3] = {"plane strain", "axisymmetric", "3D"};

static void round_trip(int dim) {
    char name[128];
    Mem a = scene(dim), b;
    MpmParticlesView v;
    Rows tail, own, other;
    MpmParticleState s;
    MpmIdRange ids;
    uint32_t removed;
    size_t n, k, half, m;
    frames("round trip: frames", a.w, 12);
    b = twin_of("round trip: twin", &a);
    ok_status("round trip: view", mpm_world_particles(a.w, &v));
    n = v.count;
    k = n / 3 + 1;
    half = (n - k) / 2;
    tail = rows_copy(a.w, k, n - k);
    snprintf(name, sizeof name, "%s: the rows that move carry a plastic history, a stress, "
             "low parts and grid values", FORMS[dim]);
    expect_true(name, any_nonzero(tail.real[COL_PLASTIC], n - k) &&
                          any_nonzero(tail.real[COL_STRESS], n - k) &&
                          any_nonzero(tail.real[COL_POSITION_LOW], n - k) &&
                          any_nonzero(tail.real[COL_TEMPERATURE + 2], n - k));
    ok_status("round trip: remove", mpm_world_remove_particles(a.w, (uint32_t)k, (uint32_t)(n - k),
                                                                &removed));
    s = rows_state(&tail, 0);
    ok_status("round trip: add first", mpm_world_add_particles_with_state(a.w, &s, half, &ids));
    snprintf(name, sizeof name, "%s: the first rows take their ids again", FORMS[dim]);
    expect_true(name, ids.first == k && ids.count == half);
    s = rows_state(&tail, half);
    ok_status("round trip: add second",
              mpm_world_add_particles_with_state(a.w, &s, n - k - half, &ids));
    snprintf(name, sizeof name, "%s: removed and added back with their state", FORMS[dim]);
    expect_same(name, a.w, b.w);
    frames("round trip: frames on", a.w, 8);
    frames("round trip: twin's frames on", b.w, 8);
    snprintf(name, sizeof name, "%s: 8 frames on", FORMS[dim]);
    expect_same(name, a.w, b.w);
    m = n / 3;
    own = rows_copy(a.w, 0, m);
    other = rows_copy(a.w, m, m);
    s = rows_state(&other, 0);
    ok_status("round trip: set another's", mpm_world_set_particle_state(a.w, 0, &s, m));
    s = rows_state(&own, 0);
    ok_status("round trip: set back", mpm_world_set_particle_state(a.w, 0, &s, m));
    snprintf(name, sizeof name, "%s: set in place to another's state and back", FORMS[dim]);
    expect_same(name, a.w, b.w);
    rows_free(&tail);
    rows_free(&own);
    rows_free(&other);
    mem_free(&a);
    mem_free(&b);
}

static void migration(int dim) {
    char name[128];
    Mem a = scene(dim), c;
    MpmWorldDef d = scene_def(dim);
    Rows all;
    MpmParticleState s;
    MpmIdRange ids;
    MpmParticlesView v;
    size_t cuts[4], j;
    frames("migration: frames", a.w, 12);
    c = world_new("migration: world", &d);
    materials("migration: materials", c.w, dim);
    frames("migration: empty frames", c.w, 12);
    ok_status("migration: view", mpm_world_particles(a.w, &v));
    cuts[0] = 0;
    cuts[1] = v.count / 4;
    cuts[2] = v.count / 2 + 3;
    cuts[3] = v.count;
    all = rows_copy(a.w, 0, v.count);
    for (j = 0; j < 3; j++) {
        s = rows_state(&all, cuts[j]);
        ok_status("migration: add", mpm_world_add_particles_with_state(c.w, &s,
                                                                       cuts[j + 1] - cuts[j], &ids));
    }
    snprintf(name, sizeof name, "%s: moved to another world", FORMS[dim]);
    expect_same(name, a.w, c.w);
    frames("migration: frames on", a.w, 8);
    frames("migration: frames on in the other world", c.w, 8);
    snprintf(name, sizeof name, "%s: moved, 8 frames on", FORMS[dim]);
    expect_same(name, a.w, c.w);
    rows_free(&all);
    mem_free(&a);
    mem_free(&c);
}

/* ---- 3. misuse ---------------------------------------------------------------------------- */

/* Rows 4 .. 12 of `w`, one value of column `col` at row 7 replaced by `value`. */
static Rows edited(const MpmWorld *w, int col, mpm_real value) {
    Rows r = rows_copy(w, 4, 8);
    r.real[col][3] = value;
    return r;
}

/* Set and add with one bad value are both refused with `want`; the same value written into a
 * snapshot's bytes is MPM_STATUS_INVALID_STATE to mpm_world_open. */
static void bad_value(const char *what, Mem *w, int col, mpm_real value, MpmStatus want) {
    char name[160];
    Rows r = edited(w->w, col, value);
    MpmParticleState s = rows_state(&r, 0);
    MpmParticlesView v;
    const mpm_real *c[REAL_COLUMNS];
    unsigned char *raw = (unsigned char *)malloc(w->bytes + 64);
    MpmWorld *opened = NULL;
    mpm_real *in_copy;
    snprintf(name, sizeof name, "set, %s", what);
    REFUSED(name, want, mpm_world_set_particle_state(w->w, 4, &s, 8));
    snprintf(name, sizeof name, "add, %s", what);
    REFUSED(name, want, mpm_world_add_particles_with_state(w->w, &s, 8, OUT(MpmIdRange)));
    if (raw == NULL) {
        fail(name, "out of memory");
    }
    ok_status(name, mpm_world_particles(w->w, &v));
    view_columns(&v, c);
    memcpy(aligned(raw, 64), w->w, w->bytes);
    in_copy = (mpm_real *)(void *)(aligned(raw, 64) +
                                   ((const unsigned char *)(c[col] + 7) -
                                    (const unsigned char *)(const void *)w->w));
    *in_copy = value;
    snprintf(name, sizeof name, "open, %s", what);
    expect_true(name, mpm_world_open(aligned(raw, 64), w->bytes, &opened) ==
                          MPM_STATUS_INVALID_STATE);
    free(raw);
    rows_free(&r);
}

static void misuse(void) {
    Mem w = scene(0);
    MpmWorldDef plain_def = scene_def(0);
    Mem plain;
    Rows r;
    MpmParticleState s, t;
    MpmParticlesView v;
    mpm_real x, ulp, nans[8];
    uint32_t status3[8], material9[8];
    MpmMaterialDef m = mpm_material_def_default();
    uint32_t id;
    int k;
    frames("misuse: frames", w.w, 4);
    track(w.w);
    r = rows_copy(w.w, 4, 8);
    s = rows_state(&r, 0);

    REFUSED("set: world NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_set_particle_state(NULL, 4, &s, 8));
    REFUSED("set: state NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_set_particle_state(w.w, 4, NULL, 8));
    REFUSED("add: world NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles_with_state(NULL, &s, 8, OUT(MpmIdRange)));
    REFUSED("add: state NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles_with_state(w.w, NULL, 8, OUT(MpmIdRange)));
    REFUSED("add: ids_out NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles_with_state(w.w, &s, 8, NULL));
    t = s;
    t.mass = NULL;
    REFUSED("add: mass NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles_with_state(w.w, &t, 8, OUT(MpmIdRange)));
    t = s;
    t.material = NULL;
    REFUSED("add: material NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles_with_state(w.w, &t, 8, OUT(MpmIdRange)));
    t = s;
    t.position[1] = NULL;
    REFUSED("add: y NULL", MPM_STATUS_NULL_POINTER,
            mpm_world_add_particles_with_state(w.w, &t, 8, OUT(MpmIdRange)));

    ok_status("misuse: view", mpm_world_particles(w.w, &v));
    t = s;
    t.mass = v.mass + 4;
    REFUSED("set: masses inside the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_set_particle_state(w.w, 4, &t, 8));
    REFUSED("add: masses inside the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_add_particles_with_state(w.w, &t, 8, OUT(MpmIdRange)));
    REFUSED("add: ids_out inside the world", MPM_STATUS_OVERLAPPING_MEMORY,
            mpm_world_add_particles_with_state(w.w, &s, 8, (MpmIdRange *)(void *)w.w));

    REFUSED("set: particles past the end", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_set_particle_state(w.w, (uint32_t)(v.count - 7), &s, 8));
    REFUSED("set: a count of SIZE_MAX reads no array", MPM_STATUS_UNKNOWN_PARTICLE,
            mpm_world_set_particle_state(w.w, 0, &s, SIZE_MAX));
    REFUSED("add: a count of SIZE_MAX reads no array", MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_add_particles_with_state(w.w, &s, SIZE_MAX, OUT(MpmIdRange)));
    REFUSED("add: one past the capacity", MPM_STATUS_PARTICLE_CAPACITY_EXCEEDED,
            mpm_world_add_particles_with_state(w.w, &s, 1024 - v.count + 1, OUT(MpmIdRange)));

    t = s;
    t.displacement_gradient[1] = NULL;
    REFUSED("set: H given in part", MPM_STATUS_LENGTH_MISMATCH,
            mpm_world_set_particle_state(w.w, 4, &t, 8));
    t = s;
    t.affine[3] = NULL;
    REFUSED("add: affine given in part", MPM_STATUS_LENGTH_MISMATCH,
            mpm_world_add_particles_with_state(w.w, &t, 8, OUT(MpmIdRange)));

    /* Arrays a plane world does not read: z, stress 4 and 5, the hoop stretch. */
    for (k = 0; k < 8; k++) {
        nans[k] = (mpm_real)NAN;
    }
    t = s;
    t.position[2] = nans;
    t.velocity[2] = nans;
    t.displacement_gradient[2] = nans;
    t.displacement_gradient[8] = nans;
    t.stress[4] = nans;
    t.stress[5] = nans;
    t.hoop = nans;
    t.affine[6] = nans;
    ACCEPTED("set: arrays a plane world does not read are not read", 0,
             mpm_world_set_particle_state(w.w, 4, &t, 8));

    /* One bad value per kind of column. */
    x = r.real[0][3];
    ulp = NEXT_UP((mpm_real)fabs((double)x)) - (mpm_real)fabs((double)x);
    bad_value("position NaN", &w, 0, (mpm_real)NAN, MPM_STATUS_NON_FINITE_INPUT);
    bad_value("position outside", &w, 1, R(5.0), MPM_STATUS_POSITION_OUTSIDE_DOMAIN);
    bad_value("low part past an ulp", &w, COL_POSITION_LOW, 4 * ulp, MPM_STATUS_INVALID_STATE);
    bad_value("velocity infinite", &w, COL_VELOCITY, (mpm_real)INFINITY,
              MPM_STATUS_NON_FINITE_INPUT);
    bad_value("mass 0", &w, COL_MASS, R(0.0), MPM_STATUS_NON_POSITIVE_MASS_OR_VOLUME);
    bad_value("H inverting F", &w, COL_H, R(-3.0), MPM_STATUS_INVALID_DEFORMATION);
    bad_value("stress NaN", &w, COL_STRESS, (mpm_real)NAN, MPM_STATUS_INVALID_DEFORMATION);
    bad_value("damping negative", &w, COL_DAMPING, R(-1.0), MPM_STATUS_INVALID_EFFECT);
    bad_value("temperature NaN", &w, COL_TEMPERATURE, (mpm_real)NAN,
              MPM_STATUS_NON_FINITE_INPUT);
    bad_value("sand history negative", &w, COL_PLASTIC, R(-0.5), MPM_STATUS_INVALID_DEFORMATION);
    bad_value("heat source infinite", &w, COL_PLASTIC + 1, (mpm_real)INFINITY,
              MPM_STATUS_NON_FINITE_INPUT);

    for (k = 0; k < 8; k++) {
        status3[k] = k == 3 ? 3 : r.status[k];
        material9[k] = k == 3 ? 9 : r.material[k];
    }
    t = s;
    t.status = status3;
    REFUSED("set: status 3", MPM_STATUS_INVALID_STATE, mpm_world_set_particle_state(w.w, 4, &t, 8));
    REFUSED("add: status 3", MPM_STATUS_INVALID_STATE,
            mpm_world_add_particles_with_state(w.w, &t, 8, OUT(MpmIdRange)));
    t = s;
    t.material = material9;
    REFUSED("set: material 9", MPM_STATUS_UNKNOWN_MATERIAL,
            mpm_world_set_particle_state(w.w, 4, &t, 8));
    REFUSED("add: material 9", MPM_STATUS_UNKNOWN_MATERIAL,
            mpm_world_add_particles_with_state(w.w, &t, 8, OUT(MpmIdRange)));

    /* A world without the effects: their arrays are refused. */
    plain_def.effects.damping.declared = 0;
    plain_def.effects.particle_forces = 0;
    plain_def.effects.heat.declared = 0;
    plain_def.effects.diffusion.declared = 0;
    plain_def.effects.plasticity = 0;
    plain_def.transfer = MPM_TRANSFER_FLIP;
    plain = world_new("misuse: plain world", &plain_def);
    ok_status("misuse: plain material", mpm_world_add_material(plain.w, &m, &id));
    track(plain.w);
    for (k = 0; k < 8; k++) {
        material9[k] = 0;
    }
    memset(&t, 0, sizeof t);
    t.position[0] = s.position[0];
    t.position[1] = s.position[1];
    t.mass = s.mass;
    t.volume0 = s.volume0;
    t.material = material9;
    t.temperature = s.temperature;
    REFUSED("add: temperature undeclared", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_particles_with_state(plain.w, &t, 8, OUT(MpmIdRange)));
    t.temperature = NULL;
    t.plastic = s.plastic;
    REFUSED("add: plastic history undeclared", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_particles_with_state(plain.w, &t, 8, OUT(MpmIdRange)));
    t.plastic = NULL;
    t.affine[0] = s.affine[0];
    REFUSED("add: affine undeclared", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_particles_with_state(plain.w, &t, 8, OUT(MpmIdRange)));
    REFUSED("add: undeclared before the capacity", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_add_particles_with_state(plain.w, &t, SIZE_MAX, OUT(MpmIdRange)));
    t.affine[0] = NULL;
    ACCEPTED("add: the rest to a world without effects", 1,
             mpm_world_add_particles_with_state(plain.w, &t, 8, OUT(MpmIdRange)));
    REFUSED("set: force undeclared", MPM_STATUS_EFFECT_NOT_DECLARED,
            mpm_world_set_particle_state(plain.w, 0, &s, 8));

    untrack(plain.w);
    untrack(w.w);
    rows_free(&r);
    mem_free(&plain);
    mem_free(&w);
}

int main(void) {
    int dim;
    for (dim = 0; dim < 3; dim++) {
        round_trip(dim);
        migration(dim);
    }
    misuse();
    printf("all %lu state checks passed\n", g_checks);
    return 0;
}
