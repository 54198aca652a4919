/*
 * Scenes stepped through the C interface, printing after every seeding call and every step
 * the FNV-1a 64 hash of the world's bytes (mpm_world_bytes extent), of every copied-out column
 * and of the columns of the borrowed view, the diagnostics and the step report, exactly (bytes
 * as hex, in memory order). tests/c_checks.rs runs the same scenes through the Rust kernel API
 * and expects the same text, line for line: the C interface must add nothing and lose nothing.
 *
 * Every number is a dyadic fraction (exact in float and double), so that a literal means the
 * same value here and in the Rust test.
 *
 * Scenes:
 *   plane2d:   a neo-Hookean block and a linear elastic disk dropped on a stick floor, plus six
 *              particles from arrays; GIMP, MUSL.
 *   space3d:   a sphere falling towards a stick floor and a box that leaves through an open
 *              face, in 3D; quadratic B-spline, USL.
 *   effects2d: a block with every effect declared: APIC, grid and particle damping schedules,
 *              a thermostat, per-particle damping, particle forces, tractions (ramped), a ramped body
 *              force, and heat conduction (a fixed floor, a flux face, sources) and diffusion
 *              (a fixed face, a flux through the floor) in a conducting material with
 *              temperatures set; forces, tractions and concentrations change halfway. GIMP,
 *              MUSL.
 *   effects3d: a sphere with APIC, constant grid damping on the nodal force and a zone of
 *              damping graded toward the floor, particle forces, tractions on two faces and a
 *              body force, in 3D; cubic B-spline, USF.
 *   axisym2d:  an axisymmetric cylinder on the axis, moving outwards, that expands with its
 *              temperatures (set, and conducted towards a fixed floor) and swells with its
 *              concentrations (diffusing in from a fixed outer face); GIMP, MUSL.
 *   cpgimp2d:  a soft block thrown onto a stick floor, where it squashes (so that its particle
 *              domains stretch); cpGIMP, USL.
 *   cpgimp3d:  a soft box thrown onto a stick floor in 3D; cpGIMP, APIC, USF.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mpm_gimp.h"

static void die(const char *what, MpmStatus s) {
    printf("FAIL %s: %s\n", what, mpm_status_string(s));
    fflush(stdout);
    exit(1);
}

#define CALL(what, call) \
    do { \
        MpmStatus s_ = (call); \
        if (s_ != MPM_STATUS_OK) { \
            die((what), s_); \
        } \
    } while (0)

static uint64_t fnv1a(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= p[i];
        h *= 0x100000001b3u;
    }
    return h;
}

#define FNV_START 0xcbf29ce484222325u

static void print_hash(uint64_t h) {
    printf("%016llx", (unsigned long long)h);
}

/* The bytes of a value, in memory order. */
static void print_bytes(const void *data, size_t n) {
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < n; i++) {
        printf("%02x", p[i]);
    }
}

static MpmVec3 v3(mpm_real x, mpm_real y, mpm_real z) {
    MpmVec3 v;
    v.x = x;
    v.y = y;
    v.z = z;
    return v;
}

static mpm_real *g_reals;
static uint32_t *g_ids;
static size_t g_capacity;

typedef MpmStatus (*CopyReal)(const MpmWorld *, mpm_real *, size_t, size_t *);

static void print_copy(const char *label, const char *name, CopyReal fn, const MpmWorld *w) {
    size_t written = 0;
    CALL(name, fn(w, g_reals, 6 * g_capacity, &written));
    printf("%s: %s ", label, name);
    print_hash(fnv1a(FNV_START, g_reals, written * sizeof(mpm_real)));
    printf(" %lu\n", (unsigned long)written);
}

/* Which pointers of the view are set: '1' set, '0' NULL. */
static void print_present(const mpm_real *const *p, size_t n) {
    size_t i;
    for (i = 0; i < n; i++) {
        putchar(p[i] != NULL ? '1' : '0');
    }
}

/* One hash over the `count` values of each column that is set, in order. */
static uint64_t hash_columns(const mpm_real *const *p, size_t n, size_t count) {
    uint64_t h = FNV_START;
    size_t i;
    for (i = 0; i < n; i++) {
        if (p[i] != NULL) {
            h = fnv1a(h, p[i], count * sizeof(mpm_real));
        }
    }
    return h;
}

static void print_state(const char *label, const MpmWorld *w) {
    size_t bytes = 0, written = 0, tractions = 0, i;
    MpmParticlesView view;
    MpmDiagnostics d;
    double alpha = 0;

    CALL("mpm_world_bytes", mpm_world_bytes(w, &bytes));
    printf("%s: world ", label);
    print_hash(fnv1a(FNV_START, w, bytes));
    printf(" %lu\n", (unsigned long)bytes);

    print_copy(label, "positions", mpm_world_copy_positions, w);
    print_copy(label, "velocities", mpm_world_copy_velocities, w);
    print_copy(label, "stress", mpm_world_copy_stress, w);
    print_copy(label, "jacobians", mpm_world_copy_jacobians, w);
    CALL("status", mpm_world_copy_status(w, g_ids, g_capacity, &written));
    printf("%s: status ", label);
    print_hash(fnv1a(FNV_START, g_ids, written * sizeof(uint32_t)));
    printf(" %lu\n", (unsigned long)written);

    CALL("mpm_world_particles", mpm_world_particles(w, &view));
    printf("%s: view count %lu dimension %u present ", label, (unsigned long)view.count,
           (unsigned)view.dimension);
    print_present(view.position, 3);
    putchar(' ');
    print_present(view.velocity, 3);
    putchar(' ');
    print_present(view.displacement_gradient, 9);
    putchar(' ');
    print_present(view.stress, 6);
    printf(" mass ");
    print_hash(fnv1a(FNV_START, view.mass, view.count * sizeof(mpm_real)));
    printf(" volume0 ");
    print_hash(fnv1a(FNV_START, view.volume0, view.count * sizeof(mpm_real)));
    printf(" material ");
    print_hash(fnv1a(FNV_START, view.material, view.count * sizeof(uint32_t)));
    printf(" displacement_gradient ");
    print_hash(hash_columns(view.displacement_gradient, 9, view.count));
    putchar('\n');

    CALL("mpm_world_traction_count", mpm_world_traction_count(w, &tractions));
    CALL("mpm_world_feedback_alpha", mpm_world_feedback_alpha(w, &alpha));
    printf("%s: effects present ", label);
    print_present(view.force, 3);
    putchar(' ');
    print_present(view.damping, 2);
    putchar(' ');
    print_present(view.affine, 9);
    printf(" force ");
    print_hash(hash_columns(view.force, 3, view.count));
    printf(" damping ");
    print_hash(hash_columns(view.damping, 2, view.count));
    printf(" affine ");
    print_hash(hash_columns(view.affine, 9, view.count));
    printf(" tractions %lu feedback_alpha ", (unsigned long)tractions);
    print_bytes(&alpha, sizeof alpha);
    putchar('\n');

    printf("%s: transport present ", label);
    print_present(&view.temperature, 1);
    print_present(&view.concentration, 1);
    print_present(&view.grid_temperature, 1);
    print_present(&view.grid_concentration, 1);
    printf(" temperature ");
    print_hash(hash_columns(&view.temperature, 1, view.count));
    printf(" concentration ");
    print_hash(hash_columns(&view.concentration, 1, view.count));
    printf(" grid_temperature ");
    print_hash(hash_columns(&view.grid_temperature, 1, view.count));
    printf(" grid_concentration ");
    print_hash(hash_columns(&view.grid_concentration, 1, view.count));
    putchar('\n');

    printf("%s: hoop present ", label);
    print_present(&view.hoop, 1);
    printf(" hoop ");
    print_hash(hash_columns(&view.hoop, 1, view.count));
    putchar('\n');

    CALL("mpm_world_diagnostics", mpm_world_diagnostics(w, &d));
    printf("%s: diagnostics particles %lu steps %lu time ", label,
           (unsigned long)d.particle_count, (unsigned long)d.step_count);
    print_bytes(&d.time, sizeof d.time);
    printf(" mass ");
    print_bytes(&d.mass, sizeof d.mass);
    printf(" momentum ");
    for (i = 0; i < 3; i++) {
        print_bytes(&d.momentum[i], sizeof d.momentum[i]);
        putchar(i < 2 ? ' ' : '\n');
    }
    printf("%s: diagnostics center_of_mass ", label);
    for (i = 0; i < 3; i++) {
        print_bytes(&d.center_of_mass[i], sizeof d.center_of_mass[i]);
        putchar(' ');
    }
    printf("kinetic ");
    print_bytes(&d.kinetic, sizeof d.kinetic);
    printf(" strain ");
    print_bytes(&d.strain, sizeof d.strain);
    printf(" potential ");
    print_bytes(&d.potential, sizeof d.potential);
    putchar('\n');
    printf("%s: diagnostics angular_momentum ", label);
    for (i = 0; i < 3; i++) {
        print_bytes(&d.angular_momentum[i], sizeof d.angular_momentum[i]);
        putchar(i < 2 ? ' ' : '\n');
    }
}

static void print_ids(const char *what, MpmIdRange ids) {
    printf("seed %s: first %lu count %lu\n", what, (unsigned long)ids.first,
           (unsigned long)ids.count);
}

static void step_frames(MpmWorld *w, int frames, mpm_real dt) {
    int f;
    uint32_t i;
    for (f = 0; f < frames; f++) {
        char label[32];
        mpm_real stable = 0;
        MpmStepReport r;
        CALL("mpm_world_stable_dt", mpm_world_stable_dt(w, &stable));
        CALL("mpm_world_step", mpm_world_step(w, dt, &r));
        printf("step %d: stable_dt ", f + 1);
        print_bytes(&stable, sizeof stable);
        printf(" substeps %lu substep_dt ", (unsigned long)r.substeps);
        print_bytes(&r.substep_dt, sizeof r.substep_dt);
        printf(" stopped %lu escaped %lu frozen %lu first_frozen", (unsigned long)r.stopped,
               (unsigned long)r.escaped, (unsigned long)r.frozen);
        for (i = 0; i < r.first_frozen_count; i++) {
            printf(" %lu", (unsigned long)r.first_frozen[i]);
        }
        putchar('\n');
        snprintf(label, sizeof label, "after step %d", f + 1);
        print_state(label, w);
    }
}

/* A world of `def` in fresh memory; the block to free goes to `raw`. */
static MpmWorld *new_world(const MpmWorldDef *def, void **raw) {
    MpmMemoryRequirements req;
    unsigned char *p;
    size_t offset;
    MpmWorld *w = NULL;
    CALL("mpm_memory_requirements", mpm_memory_requirements(def, &req));
    printf("requirements bytes %lu align %lu\n", (unsigned long)req.bytes,
           (unsigned long)req.align);
    p = (unsigned char *)malloc(req.bytes + req.align);
    if (p == NULL) {
        printf("FAIL malloc\n");
        exit(1);
    }
    offset = (req.align - (size_t)((uintptr_t)p % req.align)) % req.align;
    CALL("mpm_world_init", mpm_world_init(def, p + offset, req.bytes, &w));
    *raw = p;
    return w;
}

static void scratch(size_t capacity) {
    free(g_reals);
    free(g_ids);
    g_capacity = capacity;
    g_reals = (mpm_real *)malloc(6 * capacity * sizeof(mpm_real));
    g_ids = (uint32_t *)malloc(capacity * sizeof(uint32_t));
    if (g_reals == NULL || g_ids == NULL) {
        printf("FAIL malloc\n");
        exit(1);
    }
}

/* Starts a scene: scratch arrays for `def`'s capacity, its world, and the empty state. */
static MpmWorld *open_scene(const MpmWorldDef *def, void **raw) {
    MpmWorld *w;
    scratch(def->particle_capacity);
    w = new_world(def, raw);
    print_state("empty", w);
    return w;
}

/* A conducting, diffusing rubber: thermal diffusivity 4096 / (1000 * 512) = 0.008 m^2/s. */
static MpmMaterialDef conducting_rubber(void) {
    MpmMaterialDef rubber = mpm_material_def_default();
    rubber.heat_capacity = (mpm_real)512.0;
    rubber.conductivity = (mpm_real)4096.0;
    rubber.diffusivity = (mpm_real)0.0078125;
    return rubber;
}

static void plane2d(void) {
    MpmWorldDef def = mpm_world_def_default();
    MpmMaterialDef rubber = mpm_material_def_default();
    MpmMaterialDef soft = mpm_material_def_default();
    uint32_t id_rubber = 0, id_soft = 0, i;
    MpmIdRange ids;
    void *raw;
    MpmWorld *w;
    mpm_real x[6], y[6], vx[6], vy[6], mass[6], volume[6];
    uint32_t material[6];
    MpmParticleArrays a;

    printf("scene plane2d\n");
    def.cells[0] = 32;
    def.cells[1] = 32;
    def.cell_size = (mpm_real)0.03125;
    def.particle_capacity = 1024;
    def.material_capacity = 2;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    w = open_scene(&def, &raw);

    soft.model = MPM_MATERIAL_MODEL_LINEAR_ELASTIC;
    soft.youngs_modulus = (mpm_real)500000.0;
    soft.poisson_ratio = (mpm_real)0.25;
    soft.density = (mpm_real)750.0;
    CALL("add rubber", mpm_world_add_material(w, &rubber, &id_rubber));
    CALL("add soft", mpm_world_add_material(w, &soft, &id_soft));
    printf("materials %lu %lu\n", (unsigned long)id_rubber, (unsigned long)id_soft);

    CALL("fill_box", mpm_world_fill_box(w, v3(0.3125f, 0.0625f, 0), v3(0.5625f, 0.1875f, 0),
                                        id_rubber, v3(0, -1.0f, 0), &ids));
    print_ids("box", ids);
    print_state("after box", w);
    CALL("fill_disk", mpm_world_fill_disk(w, v3(0.75f, 0.25f, 0), (mpm_real)0.0625, id_soft,
                                          v3(-0.5f, 0, 0), &ids));
    print_ids("disk", ids);
    print_state("after disk", w);

    for (i = 0; i < 6; i++) {
        x[i] = (mpm_real)(0.125 + 0.03125 * i);
        y[i] = (mpm_real)(0.125 + 0.0625 * (i % 2));
        vx[i] = (mpm_real)(0.5 * i - 1.0);
        vy[i] = (mpm_real)0.25;
        mass[i] = (mpm_real)0.25;
        volume[i] = (mpm_real)(1.0 / 4096.0);
        material[i] = i % 2 ? id_soft : id_rubber;
    }
    a.position[0] = x;
    a.position[1] = y;
    a.position[2] = NULL;
    a.velocity[0] = vx;
    a.velocity[1] = vy;
    a.velocity[2] = NULL;
    a.mass = mass;
    a.volume = volume;
    a.material = material;
    CALL("add_particles", mpm_world_add_particles(w, &a, 6, &ids));
    print_ids("arrays", ids);
    print_state("after arrays", w);

    step_frames(w, 16, (mpm_real)0.0078125);
    free(raw);
}

static void space3d(void) {
    MpmWorldDef def = mpm_world_def_default();
    MpmMaterialDef rubber = mpm_material_def_default();
    uint32_t id = 0;
    MpmIdRange ids;
    void *raw;
    MpmWorld *w;

    printf("scene space3d\n");
    def.dimension = MPM_DIMENSION_SPACE3D;
    def.cells[0] = 12;
    def.cells[1] = 12;
    def.cells[2] = 12;
    def.cell_size = (mpm_real)0.0625;
    def.particle_capacity = 2048;
    def.material_capacity = 1;
    def.shape = MPM_SHAPE_QUADRATIC_BSPLINE;
    def.update_order = MPM_UPDATE_ORDER_USL;
    def.flip_beta = (mpm_real)0.875;
    def.pic_rate = (mpm_real)12.5;
    def.gravity = v3(0.5f, -10.0f, 0.25f);
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    def.faces[MPM_FACE_X_MAX] = MPM_BOUNDARY_OPEN;
    def.exp_terms = 3;
    def.cfl = (mpm_real)0.375;
    w = open_scene(&def, &raw);

    CALL("add rubber", mpm_world_add_material(w, &rubber, &id));
    printf("materials %lu\n", (unsigned long)id);
    CALL("fill_sphere", mpm_world_fill_sphere(w, v3(0.25f, 0.25f, 0.25f), (mpm_real)0.125,
                                              id, v3(0.5f, -0.5f, 0.25f), &ids));
    print_ids("sphere", ids);
    print_state("after sphere", w);
    CALL("fill_box", mpm_world_fill_box(w, v3(0.5f, 0.5f, 0.5f), v3(0.625f, 0.625f, 0.625f),
                                        id, v3(2.0f, 0, 0), &ids));
    print_ids("box", ids);
    print_state("after box", w);

    step_frames(w, 16, (mpm_real)0.0078125);
    free(raw);
}

/* A schedule through the first `n` of (t, v). */
static MpmSchedule schedule(unsigned n, const double *t, const double *v) {
    MpmSchedule s;
    unsigned i;
    memset(&s, 0, sizeof s);
    s.points = n;
    for (i = 0; i < n; i++) {
        s.times[i] = (mpm_real)t[i];
        s.values[i] = (mpm_real)v[i];
    }
    return s;
}

static void print_tractions(const char *what, MpmIdRange ids) {
    printf("tractions %s: first %lu count %lu\n", what, (unsigned long)ids.first,
           (unsigned long)ids.count);
}

static void effects2d(void) {
    static const double grid_t[] = {0.0, 0.0625}, grid_v[] = {0.5, 2.0};
    static const double particle_t[] = {0.0}, particle_v[] = {0.25};
    static const double ramp_t[] = {0.0, 0.03125, 0.0625}, ramp_v[] = {0.0, 1.0, 0.0};
    static const double traction_t[] = {0.0, 0.0625}, traction_v[] = {0.5, 1.5};
    MpmWorldDef def = mpm_world_def_default();
    MpmMaterialDef rubber = conducting_rubber();
    uint32_t id = 0, i, n;
    MpmIdRange ids;
    void *raw;
    MpmWorld *w;
    mpm_real fx[16], fy[16], alpha_g[32], alpha_p[32], heat[256], source[8];

    printf("scene effects2d\n");
    def.cells[0] = 32;
    def.cells[1] = 32;
    def.cell_size = (mpm_real)0.03125;
    def.particle_capacity = 256;
    def.material_capacity = 1;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    def.transfer = MPM_TRANSFER_APIC;
    def.effects.damping.declared = 1;
    def.effects.damping.grid = schedule(2, grid_t, grid_v);
    def.effects.damping.particle = schedule(1, particle_t, particle_v);
    def.effects.damping.feedback.declared = 1;
    def.effects.damping.feedback.gain = (mpm_real)0.5;
    def.effects.damping.feedback.max_alpha = (mpm_real)4.0;
    def.effects.damping.per_particle = 1;
    def.effects.particle_forces = 1;
    def.effects.traction_capacity = 16;
    def.effects.body_force = v3(0.5f, 0.25f, 0);
    def.effects.body_force_scale = schedule(3, ramp_t, ramp_v);
    def.effects.body_force_gradient[0] = v3(-2.0f, 0.5f, 0);
    def.effects.body_force_gradient[1] = v3(0.25f, 1.0f, 0);
    def.effects.traction_schedules[0] = schedule(2, traction_t, traction_v);
    def.effects.heat.declared = 1;
    def.effects.heat.faces[MPM_FACE_Y_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED;
    def.effects.heat.faces[MPM_FACE_Y_MIN].value = (mpm_real)320.0;
    def.effects.heat.faces[MPM_FACE_X_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX;
    def.effects.heat.faces[MPM_FACE_X_MIN].value = (mpm_real)-2048.0;
    def.effects.heat.sources = 1;
    def.effects.diffusion.declared = 1;
    def.effects.diffusion.faces[MPM_FACE_X_MAX].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED;
    def.effects.diffusion.faces[MPM_FACE_X_MAX].value = (mpm_real)1.0;
    def.effects.diffusion.faces[MPM_FACE_Y_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FLUX;
    def.effects.diffusion.faces[MPM_FACE_Y_MIN].value = (mpm_real)0.25;
    w = open_scene(&def, &raw);

    CALL("add rubber", mpm_world_add_material(w, &rubber, &id));
    printf("materials %lu\n", (unsigned long)id);
    CALL("fill_box", mpm_world_fill_box(w, v3(0.25f, 0.125f, 0), v3(0.5f, 0.25f, 0), id,
                                        v3(0.5f, -0.25f, 0), &ids));
    print_ids("box", ids);
    n = ids.count;

    for (i = 0; i < 16; i++) {
        fx[i] = (mpm_real)(0.0625 * i - 0.5);
        fy[i] = (mpm_real)0.125;
    }
    CALL("set_particle_forces", mpm_world_set_particle_forces(w, 0, fx, fy, NULL, 16));
    for (i = 0; i < 32; i++) {
        alpha_g[i] = (mpm_real)(0.5 * (i % 4));
        alpha_p[i] = (mpm_real)(0.25 * (i % 2));
    }
    CALL("set_particle_damping", mpm_world_set_particle_damping(w, 8, alpha_g, alpha_p, 32));
    for (i = 0; i < n; i++) {
        heat[i] = (mpm_real)(256.0 + 8.0 * (i % 8) + 0.5 * (i / 8));
    }
    CALL("set_particle_scalar temperature",
         mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, heat, n));
    for (i = 0; i < 8; i++) {
        source[i] = (mpm_real)(65536.0 * (i % 2));
    }
    CALL("set_particle_sources temperature",
         mpm_world_set_particle_sources(w, MPM_SCALAR_FIELD_TEMPERATURE, n - 8, source, 8));
    CALL("add_tractions top", mpm_world_add_tractions(w, n - 16, 16, MPM_FACE_Y_MAX,
                                                      v3(0, -512.0f, 0), &ids));
    print_tractions("top", ids);
    print_state("after effects", w);
    step_frames(w, 8, (mpm_real)0.0078125);

    for (i = 0; i < 8; i++) {
        fx[i] = (mpm_real)-0.25;
        fy[i] = (mpm_real)0.5;
    }
    CALL("set_particle_forces again", mpm_world_set_particle_forces(w, 4, fx, fy, NULL, 8));
    CALL("clear_tractions", mpm_world_clear_tractions(w));
    for (i = 0; i < 16; i++) {
        heat[i] = (mpm_real)(0.0625 * i);
    }
    CALL("set_particle_scalar concentration",
         mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_CONCENTRATION, 8, heat, 16));
    CALL("add_tractions left", mpm_world_add_tractions(w, 0, 4, MPM_FACE_X_MIN,
                                                       v3(128.0f, 0, 0), &ids));
    print_tractions("left", ids);
    print_state("after changes", w);
    step_frames(w, 8, (mpm_real)0.0078125);
    free(raw);
}

static void effects3d(void) {
    static const double one_t[] = {0.0}, one_v[] = {1.0};
    MpmWorldDef def = mpm_world_def_default();
    MpmMaterialDef rubber = mpm_material_def_default();
    uint32_t id = 0, i, n;
    MpmIdRange ids;
    void *raw;
    MpmWorld *w;
    mpm_real *f[3];

    printf("scene effects3d\n");
    def.dimension = MPM_DIMENSION_SPACE3D;
    def.cells[0] = 8;
    def.cells[1] = 8;
    def.cells[2] = 8;
    def.cell_size = (mpm_real)0.0625;
    def.particle_capacity = 512;
    def.material_capacity = 1;
    def.shape = MPM_SHAPE_CUBIC_BSPLINE;
    def.update_order = MPM_UPDATE_ORDER_USF;
    def.transfer = MPM_TRANSFER_APIC;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    def.effects.damping.declared = 1;
    def.effects.damping.grid = schedule(1, one_t, one_v);
    def.effects.damping.grid_on_force = 1;
    def.effects.damping.zone_count = 1;
    def.effects.damping.zones[0].min = v3(-1.0f, 0, -1.0f);
    def.effects.damping.zones[0].max = v3(1.0f, 0.25f, 1.0f);
    def.effects.damping.zones[0].rate = (mpm_real)3.0;
    def.effects.damping.zones[0].ramped = 1;
    def.effects.damping.zones[0].ramp_face = MPM_FACE_Y_MIN;
    def.effects.particle_forces = 1;
    def.effects.traction_capacity = 8;
    def.effects.body_force = v3(0, 0, -2.0f);
    def.effects.body_force_scale = schedule(1, one_t, one_v);
    w = open_scene(&def, &raw);

    CALL("add rubber", mpm_world_add_material(w, &rubber, &id));
    printf("materials %lu\n", (unsigned long)id);
    CALL("fill_sphere", mpm_world_fill_sphere(w, v3(0.25f, 0.25f, 0.25f), (mpm_real)0.09375,
                                              id, v3(0, -0.5f, 0.25f), &ids));
    print_ids("sphere", ids);
    n = ids.count;
    for (i = 0; i < 3; i++) {
        f[i] = g_reals + i * n;
    }
    for (i = 0; i < n; i++) {
        f[0][i] = 0;
        f[1][i] = (mpm_real)(0.0625 * (i % 3));
        f[2][i] = (mpm_real)-0.125;
    }
    CALL("set_particle_forces", mpm_world_set_particle_forces(w, 0, f[0], f[1], f[2], n));
    CALL("add_tractions top", mpm_world_add_tractions(w, 0, 4, MPM_FACE_Z_MAX,
                                                      v3(0, 0, -256.0f), &ids));
    print_tractions("top", ids);
    CALL("add_tractions side", mpm_world_add_tractions(w, 4, 4, MPM_FACE_X_MIN,
                                                       v3(64.0f, 0, 32.0f), &ids));
    print_tractions("side", ids);
    print_state("after effects", w);
    step_frames(w, 8, (mpm_real)0.0078125);
    free(raw);
}

static void axisym2d(void) {
    MpmWorldDef def = mpm_world_def_default();
    MpmMaterialDef rubber = conducting_rubber();
    uint32_t id = 0, i, n;
    MpmIdRange ids;
    void *raw;
    MpmWorld *w;
    mpm_real *values;

    printf("scene axisym2d\n");
    def.dimension = MPM_DIMENSION_AXISYMMETRIC2D;
    /* GIMP's margin is one cell: the lower x face's wall plane is the axis r = 0. */
    def.origin = v3(-0.03125f, 0, 0);
    def.cells[0] = 16;
    def.cells[1] = 16;
    def.cell_size = (mpm_real)0.03125;
    def.particle_capacity = 512;
    def.material_capacity = 1;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    def.effects.heat.declared = 1;
    def.effects.heat.faces[MPM_FACE_Y_MIN].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED;
    def.effects.heat.faces[MPM_FACE_Y_MIN].value = (mpm_real)320.0;
    def.effects.diffusion.declared = 1;
    def.effects.diffusion.faces[MPM_FACE_X_MAX].kind = MPM_SCALAR_BOUNDARY_KIND_FIXED;
    def.effects.diffusion.faces[MPM_FACE_X_MAX].value = (mpm_real)1.0;
    w = open_scene(&def, &raw);

    /* The conducting rubber, stress-free at 256 K and no concentration; 56 K more is a strain
       of 1.4 %. */
    rubber.thermal_expansion = (mpm_real)(1.0 / 4096.0);
    rubber.reference_temperature = (mpm_real)256.0;
    rubber.swelling = (mpm_real)0.03125;
    rubber.reference_concentration = (mpm_real)0.0;
    CALL("add rubber", mpm_world_add_material(w, &rubber, &id));
    printf("materials %lu\n", (unsigned long)id);
    CALL("fill_box", mpm_world_fill_box(w, v3(0, 0.0625f, 0), v3(0.25f, 0.25f, 0), id,
                                        v3(0.25f, -0.5f, 0), &ids));
    print_ids("box", ids);
    print_state("after box", w);
    n = ids.count;

    values = g_reals;
    for (i = 0; i < n; i++) {
        values[i] = (mpm_real)(256.0 + 8.0 * (i % 8));
    }
    CALL("set_particle_scalar temperature",
         mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_TEMPERATURE, 0, values, n));
    for (i = 0; i < n; i++) {
        values[i] = (mpm_real)(0.0625 * (i % 16));
    }
    CALL("set_particle_scalar concentration",
         mpm_world_set_particle_scalar(w, MPM_SCALAR_FIELD_CONCENTRATION, 0, values, n));
    print_state("after scalars", w);
    step_frames(w, 12, (mpm_real)0.0078125);
    free(raw);
}

/* cpGIMP's domains follow F: a soft block squashed on the floor. */
static void cpgimp(MpmDimension dimension) {
    MpmWorldDef def = mpm_world_def_default();
    MpmMaterialDef soft = mpm_material_def_default();
    uint32_t id = 0;
    MpmIdRange ids;
    void *raw;
    MpmWorld *w;
    const int three = dimension == MPM_DIMENSION_SPACE3D;

    printf(three ? "scene cpgimp3d\n" : "scene cpgimp2d\n");
    def.dimension = dimension;
    def.cells[0] = three ? 8 : 16;
    def.cells[1] = three ? 8 : 16;
    def.cells[2] = three ? 8 : 1;
    def.cell_size = (mpm_real)0.0625;
    def.particle_capacity = 256;
    def.material_capacity = 1;
    def.shape = MPM_SHAPE_CP_GIMP;
    def.update_order = three ? MPM_UPDATE_ORDER_USF : MPM_UPDATE_ORDER_USL;
    def.transfer = three ? MPM_TRANSFER_APIC : MPM_TRANSFER_FLIP_PARTICLE_VELOCITY;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    w = open_scene(&def, &raw);

    soft.youngs_modulus = (mpm_real)500000.0;
    soft.poisson_ratio = (mpm_real)0.25;
    soft.density = (mpm_real)750.0;
    CALL("add soft", mpm_world_add_material(w, &soft, &id));
    printf("materials %lu\n", (unsigned long)id);
    if (three) {
        CALL("fill_box", mpm_world_fill_box(w, v3(0.125f, 0.125f, 0.125f),
                                            v3(0.25f, 0.25f, 0.25f), id,
                                            v3(0.5f, -2.0f, 0.25f), &ids));
    } else {
        CALL("fill_box", mpm_world_fill_box(w, v3(0.25f, 0.125f, 0), v3(0.5f, 0.375f, 0), id,
                                            v3(0.5f, -2.0f, 0), &ids));
    }
    print_ids("box", ids);
    print_state("after box", w);
    step_frames(w, three ? 12 : 16, (mpm_real)0.0078125);
    free(raw);
}

int main(void) {
    plane2d();
    space3d();
    effects2d();
    effects3d();
    axisym2d();
    cpgimp(MPM_DIMENSION_PLANE2D);
    cpgimp(MPM_DIMENSION_SPACE3D);
    free(g_reals);
    free(g_ids);
    printf("end\n");
    return 0;
}
