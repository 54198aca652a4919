/*
 * What the C check programs (misuse.c, hostile.c) share: reporting, the hash of tracked
 * worlds, the output sentinel, and the two kinds of check (a refused call changes no world
 * and writes no output; an accepted one does or does not change the tracked worlds as told).
 * Every function is static inline, so a program that leaves one unused builds without a
 * warning. Include it after mpm_gimp.h and the C library headers.
 */
#ifndef MPM_GIMP_TESTS_CHECK_H
#define MPM_GIMP_TESTS_CHECK_H

/* ---- reporting ------------------------------------------------------------------------- */

static unsigned long g_checks;

static inline void fail(const char *name, const char *why) {
    printf("FAIL %s: %s\n", name, why);
    fflush(stdout);
    exit(1);
}

static inline void pass(const char *name, MpmStatus s) {
    g_checks++;
    printf("ok %s: %s\n", name, mpm_status_string(s));
}

static inline void expect_true(const char *name, int ok) {
    if (!ok) {
        fail(name, "condition false");
    }
    g_checks++;
    printf("ok %s\n", name);
}

/* ---- hashing and tracked worlds ------------------------------------------------------- */

static inline uint64_t fnv1a(const void *data, size_t n) {
    const unsigned char *p = (const unsigned char *)data;
    uint64_t h = UINT64_C(0xcbf29ce484222325);
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= p[i];
        h *= UINT64_C(0x100000001b3);
    }
    return h;
}

/* The world's extent, mpm_world_bytes (which covers the header and every column). */
static inline size_t world_extent(const MpmWorld *w) {
    size_t n = 0;
    if (mpm_world_bytes(w, &n) != MPM_STATUS_OK) {
        fail("world_extent", "mpm_world_bytes refused a world");
    }
    return n;
}

static inline uint64_t world_hash(const MpmWorld *w) { return fnv1a(w, world_extent(w)); }

/* The worlds every check compares, with their hashes after the last accepted change. */
#define MAX_TRACKED 16
static const MpmWorld *g_tracked[MAX_TRACKED];
static uint64_t g_hash[MAX_TRACKED];
static int g_tracked_count;

static inline void track(const MpmWorld *w) {
    if (g_tracked_count == MAX_TRACKED) {
        fail("track", "too many tracked worlds");
    }
    g_tracked[g_tracked_count] = w;
    g_hash[g_tracked_count] = world_hash(w);
    g_tracked_count++;
}

static inline void untrack(const MpmWorld *w) {
    int i;
    for (i = 0; i < g_tracked_count; i++) {
        if (g_tracked[i] == w) {
            g_tracked[i] = g_tracked[g_tracked_count - 1];
            g_hash[i] = g_hash[g_tracked_count - 1];
            g_tracked_count--;
            return;
        }
    }
}

/* Whether any tracked world changed; records the new hashes. */
static inline int rehash(void) {
    int i, changed = 0;
    for (i = 0; i < g_tracked_count; i++) {
        uint64_t h = world_hash(g_tracked[i]);
        changed |= h != g_hash[i];
        g_hash[i] = h;
    }
    return changed;
}

/* ---- output sentinel ------------------------------------------------------------------ */

#define OUT_BYTES 8192
#define OUT_FILL 0xA5
static union {
    unsigned char bytes[OUT_BYTES];
    double d;
    uint64_t u;
    size_t s;
    void *p;
} g_out;

/* Pointers into the sentinel area, suitably aligned for any output type. */
#define OUT(T) ((T *)(void *)g_out.bytes)
#define OUT_AT(T, offset) ((T *)(void *)(g_out.bytes + (offset)))
/* The copy-out tests put `out` at the start and `written_out` here. */
#define WRITTEN_AT (OUT_BYTES - 64)

static inline void out_reset(void) { memset(g_out.bytes, OUT_FILL, OUT_BYTES); }

static inline int out_untouched(void) {
    size_t i;
    for (i = 0; i < OUT_BYTES; i++) {
        if (g_out.bytes[i] != OUT_FILL) {
            return 0;
        }
    }
    return 1;
}

/* Memory a program fills with PATTERN to see that a call left it alone. */
#define PATTERN 0xC3

static inline int pattern_intact(const unsigned char *p, size_t n) {
    size_t i;
    for (i = 0; i < n; i++) {
        if (p[i] != PATTERN) {
            return 0;
        }
    }
    return 1;
}

/* ---- the two kinds of check ----------------------------------------------------------- */

/* A further check of memory a refused call must leave alone, set by a program that has some
 * (NULL: none); it answers whether that memory is intact. */
static int (*g_also_intact)(void);

static inline void refused_check(const char *name, MpmStatus want, MpmStatus got) {
    char why[256];
    if (got != want) {
        snprintf(why, sizeof why, "expected status %u (%s), got %u (%s)", (unsigned)want,
                 mpm_status_string(want), (unsigned)got, mpm_status_string(got));
        fail(name, why);
    }
    if (!out_untouched()) {
        fail(name, "the refused call wrote an output");
    }
    if (g_also_intact != NULL && !g_also_intact()) {
        fail(name, "the refused call wrote to the caller's memory around the world");
    }
    if (rehash()) {
        fail(name, "the refused call changed a world's bytes");
    }
    pass(name, got);
}

/* `call` is evaluated after the sentinel is reset. */
#define REFUSED(name, want, call) refused_check((name), (want), (out_reset(), (call)))

/* An accepted call; `changes` is 1 if it must change a tracked world, 0 if it must not (so
 * that the hash comparison of the refused calls is shown to see changes), -1 if either is
 * fine. */
static inline void accepted_check(const char *name, int changes, MpmStatus got) {
    char why[256];
    int changed;
    if (got != MPM_STATUS_OK) {
        snprintf(why, sizeof why, "expected MPM_STATUS_OK, got %u (%s)", (unsigned)got,
                 mpm_status_string(got));
        fail(name, why);
    }
    changed = rehash();
    if (changes >= 0 && changed != changes) {
        fail(name, changes ? "the accepted call did not change the world's bytes"
                           : "the accepted call changed a world's bytes");
    }
    pass(name, got);
}

#define ACCEPTED(name, changes, call) accepted_check((name), (changes), (call))

/* ---- values --------------------------------------------------------------------------- */

static inline mpm_real R(double x) { return (mpm_real)x; }

static inline MpmVec3 v3(double x, double y, double z) {
    MpmVec3 v;
    v.x = R(x);
    v.y = R(y);
    v.z = R(z);
    return v;
}

/* The programs' 2D grid: 20 x 20 cells of 0.05 m (GIMP: particles admitted in
 * [0.05, 0.95]), with room for `particles` particles and `materials` materials. */
static inline MpmWorldDef grid_2d(uint32_t particles, uint32_t materials) {
    MpmWorldDef d = mpm_world_def_default();
    d.cells[0] = 20;
    d.cells[1] = 20;
    d.cell_size = R(0.05);
    d.particle_capacity = particles;
    d.material_capacity = materials;
    return d;
}

/* Declares every effect in a 2D definition: APIC, damping (a constant grid schedule, a
 * thermostat, per-particle columns), particle forces, 8 tractions, a body force, heat
 * conduction (a fixed floor, a flux face) and diffusion, both with sources. */
static inline void declare_every_effect(MpmWorldDef *def) {
    MpmWorldDef d = *def;
    d.transfer = MPM_TRANSFER_APIC;
    d.effects.damping.declared = 1;
    d.effects.damping.grid.points = 1;
    d.effects.damping.grid.values[0] = R(1.0);
    d.effects.damping.feedback.declared = 1;
    d.effects.damping.feedback.gain = R(1.0);
    d.effects.damping.feedback.max_alpha = R(8.0);
    d.effects.damping.per_particle = 1;
    d.effects.particle_forces = 1;
    d.effects.traction_capacity = 8;
    d.effects.body_force = v3(0.5, 0.0, 0.0);
    d.effects.body_force_scale.points = 1;
    d.effects.body_force_scale.values[0] = R(1.0);
    d.effects.heat.declared = 1;
    d.effects.heat.faces[MPM_FACE_Y_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED;
    d.effects.heat.faces[MPM_FACE_Y_MIN].value = R(300.0);
    d.effects.heat.faces[MPM_FACE_X_MAX].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX;
    d.effects.heat.faces[MPM_FACE_X_MAX].value = R(10.0);
    d.effects.heat.sources = 1;
    d.effects.diffusion.declared = 1;
    d.effects.diffusion.sources = 1;
    *def = d;
}

#endif
