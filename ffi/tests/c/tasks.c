/*
 * mpm_world_step_tasks from C, on a pool of worker threads that this program runs.
 *
 * Same state: each scene is stepped with mpm_world_step, then in a fresh world on a host that
 * runs every task on the calling thread, then on pools of 1, 2, 3, 4, 7, 8 and 16 threads
 * cutting the items two ways (one range per worker; ranges of min_range items taken in turn
 * by whichever thread is free). After every frame the state (every column of the particle
 * view, the diagnostics) and the step report must hash the same as mpm_world_step's, bit for
 * bit. Every world has the definition's workers = 16.
 *
 * Misuse: NULL world, task system, callback or report, a worker_count of 0, past the
 * definition's workers or UINT32_MAX, a bad dt, a dt past max_substeps, a report inside the
 * world and memory that is not a world are refused with their status, change no world's bytes,
 * write no report and call no callback (but the dt past max_substeps, which the step learns
 * from its scan of the particles for the stable step, a scan that runs on the task system).
 *
 * Hostile hosts: a host that calls the task past the items, with a worker index past
 * worker_count, leaves the last item out, runs the first item twice, or runs some ranges twice
 * and leaves as many items out (the count of items run is the task's item count) makes the
 * step answer MPM_STATUS_TASK_CONTRACT without a report, once the kernel hands it a task (of
 * two items or more, for the last). (A kernel whose step hands out no task, as the serial
 * kernel does, steps as usual: then the check is that the step succeeds; each check says
 * which case it met.) The world may then be in an intermediate state, as the header says: a
 * snapshot taken before the step, copied back, opens and steps as the world it was.
 *
 * One line per check ("ok <name>..."); the first failure prints "FAIL <name>: <why>" and
 * exits with status 1. The last line on success is "all <n> tasks checks passed".
 * tests/c_checks.rs builds this file with strict warnings and with AddressSanitizer and
 * UndefinedBehaviorSanitizer, and runs it.
 */
/* pthreads and posix_memalign under -std=c99. */
#define _POSIX_C_SOURCE 200809L

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mpm_gimp.h"

#include "check.h"

#define DEF_WORKERS 16
#define FRAMES 5

/* ---- a pool of worker threads -------------------------------------------------------- */

/* How a pool cuts a task's items. */
typedef enum { CUT_EVEN, CUT_FINE } Cut;

typedef struct Pool Pool;

typedef struct {
    Pool *pool;
    uint32_t index;
    pthread_t thread;
} Worker;

struct Pool {
    pthread_mutex_t lock;
    pthread_cond_t work; /* a task was queued, or the pool stops */
    pthread_cond_t idle; /* the task's last range has returned */
    Cut cut;
    uint32_t workers;
    /* The task being run: ranges of `len` items from `next` on, `running` of them taken and
     * not yet returned. */
    MpmTaskCallback *task;
    void *context;
    uint32_t items, len, next, running;
    int stop;
    unsigned long tasks; /* tasks received */
    Worker threads[DEF_WORKERS];
};

static void *worker_main(void *arg) {
    Worker *self = (Worker *)arg;
    Pool *p = self->pool;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        uint32_t start, end;
        while ((p->task == NULL || p->next == p->items) && !p->stop) {
            pthread_cond_wait(&p->work, &p->lock);
        }
        if (p->stop) {
            break;
        }
        start = p->next;
        end = p->items - start > p->len ? start + p->len : p->items;
        p->next = end;
        p->running++;
        pthread_mutex_unlock(&p->lock);
        p->task(start, end, self->index, p->context);
        pthread_mutex_lock(&p->lock);
        p->running--;
        if (p->next == p->items && p->running == 0) {
            p->task = NULL;
            pthread_cond_signal(&p->idle);
        }
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

static void *pool_enqueue(MpmTaskCallback *task, uint32_t item_count, uint32_t min_range,
                          void *task_context, void *user_context) {
    Pool *p = (Pool *)user_context;
    uint32_t min = min_range > 0 ? min_range : 1;
    uint32_t ranges = item_count / min;
    if (ranges > p->workers) {
        ranges = p->workers;
    }
    if (ranges == 0) {
        ranges = 1;
    }
    pthread_mutex_lock(&p->lock);
    p->tasks++;
    p->task = task;
    p->context = task_context;
    p->items = item_count;
    p->next = 0;
    p->running = 0;
    p->len = p->cut == CUT_FINE ? min : item_count / ranges + (item_count % ranges != 0);
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->lock);
    return p;
}

static void pool_finish(void *user_task, void *user_context) {
    Pool *p = (Pool *)user_task;
    (void)user_context;
    pthread_mutex_lock(&p->lock);
    while (p->task != NULL) {
        pthread_cond_wait(&p->idle, &p->lock);
    }
    pthread_mutex_unlock(&p->lock);
}

static void pool_start(Pool *p, uint32_t workers, Cut cut) {
    uint32_t i;
    memset(p, 0, sizeof *p);
    p->workers = workers;
    p->cut = cut;
    if (pthread_mutex_init(&p->lock, NULL) != 0 || pthread_cond_init(&p->work, NULL) != 0 ||
        pthread_cond_init(&p->idle, NULL) != 0) {
        fail("pool_start", "pthread init failed");
    }
    for (i = 0; i < workers; i++) {
        p->threads[i].pool = p;
        p->threads[i].index = i;
        if (pthread_create(&p->threads[i].thread, NULL, worker_main, &p->threads[i]) != 0) {
            fail("pool_start", "pthread_create failed");
        }
    }
}

static void pool_stop(Pool *p) {
    uint32_t i;
    pthread_mutex_lock(&p->lock);
    p->stop = 1;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->lock);
    for (i = 0; i < p->workers; i++) {
        pthread_join(p->threads[i].thread, NULL);
    }
    pthread_cond_destroy(&p->idle);
    pthread_cond_destroy(&p->work);
    pthread_mutex_destroy(&p->lock);
}

static MpmTaskSystem pool_system(Pool *p) {
    MpmTaskSystem t;
    t.enqueue_task = pool_enqueue;
    t.finish_task = pool_finish;
    t.user_context = p;
    t.worker_count = p->workers;
    return t;
}

/* ---- hosts on the calling thread ----------------------------------------------------- */

/* What a host that runs tasks on the calling thread does with them. */
typedef enum {
    HOST_INLINE,     /* the whole task, as worker 0 */
    HOST_PAST_END,   /* the items, then one range past them */
    HOST_BAD_WORKER, /* the items, on worker index worker_count */
    HOST_SKIP_LAST,  /* every item but the last */
    HOST_TWICE,      /* the items, then the first one again */
    HOST_SAME_COUNT, /* ranges cut in pairs: the first of each twice, the second left out */
    HOST_COUNT
} HostMode;

static const char *const HOST_NAMES[HOST_COUNT] = {
    "inline", "past the end", "worker index past worker_count", "last item left out",
    "first item run twice", "ranges run twice and as many items left out",
};

typedef struct {
    HostMode mode;
    uint32_t worker_count;
    unsigned long tasks;    /* tasks received */
    unsigned long finishes; /* finish calls */
    unsigned long twisted;  /* tasks whose ranges broke the contract (HOST_SAME_COUNT) */
} Host;

/* HOST_SAME_COUNT: ranges of `len` items (min_range, at most half the items), taken in pairs
 * of equal length: the first of a pair runs twice (on worker 0, then on worker 1) and the
 * second not at all; the items of a pair's first range run from its start on, the rest of the
 * task (less than a pair) once. The ranges' lengths add up to item_count. A task of one item
 * runs as a whole. */
static void same_count(Host *h, MpmTaskCallback *task, uint32_t items, uint32_t min_range,
                       void *context) {
    uint32_t len = min_range < items / 2 ? min_range : items / 2;
    uint32_t at = 0;
    if (len == 0) {
        task(0, items, 0, context);
        return;
    }
    h->twisted++;
    for (; items - at >= 2 * len; at += 2 * len) {
        task(at, at + len, 0, context);
        task(at, at + len, 1 % h->worker_count, context);
    }
    if (at < items) {
        task(at, items, 0, context);
    }
}

static void *host_enqueue(MpmTaskCallback *task, uint32_t item_count, uint32_t min_range,
                          void *task_context, void *user_context) {
    Host *h = (Host *)user_context;
    h->tasks++;
    switch (h->mode) {
    case HOST_INLINE:
        task(0, item_count, 0, task_context);
        break;
    case HOST_PAST_END:
        task(0, item_count, 0, task_context);
        task(item_count, item_count + 1, 0, task_context);
        break;
    case HOST_BAD_WORKER:
        task(0, item_count, h->worker_count, task_context);
        break;
    case HOST_SKIP_LAST:
        task(0, item_count - 1, 0, task_context);
        break;
    case HOST_TWICE:
        task(0, item_count, 0, task_context);
        task(0, 1, 0, task_context);
        break;
    case HOST_SAME_COUNT:
        same_count(h, task, item_count, min_range, task_context);
        break;
    default:
        break;
    }
    return NULL;
}

static void host_finish(void *user_task, void *user_context) {
    Host *h = (Host *)user_context;
    (void)user_task;
    h->finishes++;
}

static MpmTaskSystem host_system(Host *h) {
    MpmTaskSystem t;
    t.enqueue_task = host_enqueue;
    t.finish_task = host_finish;
    t.user_context = h;
    t.worker_count = h->worker_count;
    return t;
}

/* ---- worlds and their state ---------------------------------------------------------- */

static void must(const char *name, MpmStatus s) {
    if (s != MPM_STATUS_OK) {
        fail(name, mpm_status_string(s));
    }
}

/* A world of `def` in fresh memory (free it with free()). */
static MpmWorld *new_world(const MpmWorldDef *def) {
    MpmMemoryRequirements req;
    void *memory = NULL;
    MpmWorld *w = NULL;
    must("mpm_memory_requirements", mpm_memory_requirements(def, &req));
    if (posix_memalign(&memory, req.align < sizeof(void *) ? sizeof(void *) : req.align,
                       req.bytes) != 0) {
        fail("posix_memalign", "out of memory");
    }
    must("mpm_world_init", mpm_world_init(def, memory, req.bytes, &w));
    return w;
}

static uint64_t fnv(uint64_t h, const void *data, size_t n) {
    const unsigned char *p = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= p[i];
        h *= UINT64_C(0x100000001b3);
    }
    return h;
}

static uint64_t columns(uint64_t h, const mpm_real *const *cols, size_t n, size_t count) {
    size_t i;
    for (i = 0; i < n; i++) {
        unsigned char present = cols[i] != NULL;
        h = fnv(h, &present, 1);
        if (cols[i] != NULL) {
            h = fnv(h, cols[i], count * sizeof(mpm_real));
        }
    }
    return h;
}

/* The hash of the world's state, as the host reads it: every column of the particle view
 * (which ones are present, and their values) and the diagnostics; then the step report. */
static uint64_t state_hash(const MpmWorld *w, const MpmStepReport *report) {
    MpmParticlesView v;
    MpmDiagnostics d;
    uint64_t h = UINT64_C(0xcbf29ce484222325);
    const mpm_real *single[9];
    must("mpm_world_particles", mpm_world_particles(w, &v));
    must("mpm_world_diagnostics", mpm_world_diagnostics(w, &d));
    h = fnv(h, &v.count, sizeof v.count);
    h = columns(h, v.position, 3, v.count);
    h = columns(h, v.position_low, 3, v.count);
    h = columns(h, v.velocity, 3, v.count);
    h = columns(h, v.displacement_gradient, 9, v.count);
    h = columns(h, v.stress, 6, v.count);
    h = columns(h, v.force, 3, v.count);
    h = columns(h, v.damping, 2, v.count);
    h = columns(h, v.affine, 9, v.count);
    single[0] = v.mass;
    single[1] = v.volume0;
    single[2] = v.temperature;
    single[3] = v.concentration;
    single[4] = v.grid_temperature;
    single[5] = v.grid_concentration;
    single[6] = v.hoop;
    single[7] = v.plastic;
    h = columns(h, single, 8, v.count);
    h = fnv(h, v.material, v.count * sizeof(uint32_t));
    h = fnv(h, v.status, v.count * sizeof(uint32_t));
    h = fnv(h, &d, sizeof d); /* 8-byte fields only: no padding */
    if (report != NULL) {
        /* Field by field: in double precision the struct has padding after `substeps`. */
        h = fnv(h, &report->substeps, sizeof report->substeps);
        h = fnv(h, &report->substep_dt, sizeof report->substep_dt);
        h = fnv(h, &report->stopped, sizeof report->stopped);
        h = fnv(h, &report->escaped, sizeof report->escaped);
        h = fnv(h, &report->frozen, sizeof report->frozen);
        h = fnv(h, &report->runaway, sizeof report->runaway);
        h = fnv(h, &report->flags, sizeof report->flags);
        h = fnv(h, &report->first_frozen_count, sizeof report->first_frozen_count);
        h = fnv(h, report->first_frozen, sizeof report->first_frozen);
    }
    return h;
}

/* ---- scenes ---------------------------------------------------------------------------- */

typedef struct {
    const char *name;
    MpmWorldDef def;
    int three_d;
} Scene;

/* A soft rubber (0.1 MPa) that conducts and diffuses: long stable substeps. */
static MpmMaterialDef rubber(void) {
    MpmMaterialDef m = mpm_material_def_default();
    m.youngs_modulus = R(1e5);
    m.heat_capacity = R(512.0);
    m.conductivity = R(4.0);
    m.diffusivity = R(1e-3);
    return m;
}

/* The scene's world, seeded, or NULL. */
static MpmWorld *seed(const Scene *s) {
    MpmWorld *w = new_world(&s->def);
    MpmMaterialDef m = rubber();
    uint32_t id = 0;
    MpmIdRange ids;
    must("mpm_world_add_material", mpm_world_add_material(w, &m, &id));
    if (s->three_d) {
        must("mpm_world_fill_sphere",
             mpm_world_fill_sphere(w, v3(0.5, 0.5, 0.5), R(0.25), id, v3(0.5, -1.0, 0.25), &ids));
        must("mpm_world_fill_box", mpm_world_fill_box(w, v3(0.25, 0.1875, 0.25),
                                                      v3(0.75, 0.25, 0.75), id, v3(0, 0, 0), &ids));
    } else {
        must("mpm_world_fill_box", mpm_world_fill_box(w, v3(0.25, 0.5, 0), v3(0.75, 0.875, 0), id,
                                                      v3(0.5, -1.0, 0), &ids));
        must("mpm_world_fill_disk",
             mpm_world_fill_disk(w, v3(0.5, 0.25, 0), R(0.125), id, v3(0, 0, 0), &ids));
    }
    return w;
}

static Scene plane2d(void) {
    Scene s;
    s.name = "plane2d";
    s.def = mpm_world_def_default();
    s.def.cells[0] = 48;
    s.def.cells[1] = 48;
    s.def.cell_size = R(1.0 / 48);
    s.def.particle_capacity = 8192;
    s.def.material_capacity = 1;
    s.def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    s.def.workers = DEF_WORKERS;
    s.three_d = 0;
    return s;
}

/* Every effect declared (check.h), in 2D. */
static Scene effects2d(void) {
    Scene s = plane2d();
    s.name = "effects2d";
    declare_every_effect(&s.def);
    s.def.workers = DEF_WORKERS;
    return s;
}

static Scene space3d(void) {
    Scene s;
    s.name = "space3d";
    s.def = mpm_world_def_default();
    s.def.dimension = MPM_DIMENSION_SPACE3D;
    s.def.cells[0] = 16;
    s.def.cells[1] = 16;
    s.def.cells[2] = 16;
    s.def.cell_size = R(1.0 / 16);
    s.def.particle_capacity = 16384;
    s.def.material_capacity = 1;
    s.def.shape = MPM_SHAPE_QUADRATIC_BSPLINE;
    s.def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    s.def.workers = DEF_WORKERS;
    s.three_d = 1;
    return s;
}

/* ---- same state ------------------------------------------------------------------------ */

/* The state hash after each frame of mpm_world_step. */
static void reference(const Scene *s, uint64_t hashes[FRAMES]) {
    MpmWorld *w = seed(s);
    int f;
    for (f = 0; f < FRAMES; f++) {
        MpmStepReport r;
        must("mpm_world_step", mpm_world_step(w, R(1.0 / 60), &r));
        hashes[f] = state_hash(w, &r);
    }
    free(w);
}

/* Steps the scene on `tasks` and compares each frame with `want`. */
static void same_state(const Scene *s, const MpmTaskSystem *tasks, const uint64_t want[FRAMES],
                       const char *host, unsigned long *received) {
    MpmWorld *w = seed(s);
    unsigned long before = *received;
    char name[160];
    int f;
    for (f = 0; f < FRAMES; f++) {
        MpmStepReport r;
        MpmStatus st = mpm_world_step_tasks(w, R(1.0 / 60), tasks, &r);
        snprintf(name, sizeof name, "%s on %s, frame %d", s->name, host, f + 1);
        must(name, st);
        if (state_hash(w, &r) != want[f]) {
            fail(name, "the state differs from mpm_world_step's");
        }
    }
    free(w);
    g_checks++;
    printf("ok %s on %s: the state of mpm_world_step after %d frames (%lu tasks)\n", s->name,
           host, FRAMES, *received - before);
}

static void same_state_everywhere(const Scene *s) {
    static const uint32_t counts[] = {1, 2, 3, 4, 7, 8, 16};
    uint64_t want[FRAMES];
    Host inline_host;
    MpmTaskSystem t;
    size_t i;
    int cut;
    reference(s, want);

    memset(&inline_host, 0, sizeof inline_host);
    inline_host.mode = HOST_INLINE;
    inline_host.worker_count = 1;
    t = host_system(&inline_host);
    same_state(s, &t, want, "the calling thread", &inline_host.tasks);
    if (inline_host.finishes != 0) {
        fail(s->name, "finish called for a task that enqueue ran");
    }

    for (cut = CUT_EVEN; cut <= CUT_FINE; cut++) {
        for (i = 0; i < sizeof counts / sizeof counts[0]; i++) {
            Pool pool;
            char host[64];
            pool_start(&pool, counts[i], (Cut)cut);
            t = pool_system(&pool);
            snprintf(host, sizeof host, "%u workers (%s ranges)", (unsigned)counts[i],
                     cut == CUT_EVEN ? "even" : "fine");
            same_state(s, &t, want, host, &pool.tasks);
            pool_stop(&pool);
        }
    }
}

/* ---- misuse ---------------------------------------------------------------------------- */

/* Calls of the counting system's callbacks. */
static unsigned long g_enqueues, g_finishes;

static void *counting_enqueue(MpmTaskCallback *task, uint32_t item_count, uint32_t min_range,
                              void *task_context, void *user_context) {
    (void)min_range;
    (void)user_context;
    g_enqueues++;
    task(0, item_count, 0, task_context);
    return NULL;
}

static void counting_finish(void *user_task, void *user_context) {
    (void)user_task;
    (void)user_context;
    g_finishes++;
}

static void refused_tasks(const char *name, MpmStatus want, MpmStatus got, int may_scan) {
    refused_check(name, want, got);
    if (!may_scan && (g_enqueues != 0 || g_finishes != 0)) {
        fail(name, "the refused call called the task system");
    }
    g_enqueues = 0;
    g_finishes = 0;
}

/* `call` is evaluated after the output sentinel is reset (check.h's REFUSED). */
#define refused(name, want, call) refused_tasks((name), (want), (out_reset(), (call)), 0)
/* The same for a call refused after the stable step's scan, which may use the task system. */
#define refused_after_scan(name, want, call) \
    refused_tasks((name), (want), (out_reset(), (call)), 1)

static void misuse(void) {
    MpmWorldDef def = grid_2d(256, 1);
    MpmWorld *w, *other;
    MpmMaterialDef m = rubber();
    MpmTaskSystem t, bad;
    MpmIdRange ids;
    uint32_t id = 0;
    void *not_world = NULL;
    def.workers = 2;
    def.max_substeps = 4;
    w = new_world(&def);
    must("mpm_world_add_material", mpm_world_add_material(w, &m, &id));
    must("mpm_world_fill_box",
         mpm_world_fill_box(w, v3(0.3, 0.3, 0), v3(0.6, 0.6, 0), id, v3(0, 0, 0), &ids));
    /* A second world that no call here may change. */
    other = new_world(&def);
    must("mpm_world_add_material", mpm_world_add_material(other, &m, &id));
    must("mpm_world_fill_box",
         mpm_world_fill_box(other, v3(0.4, 0.4, 0), v3(0.5, 0.5, 0), id, v3(0, 0, 0), &ids));
    track(w);
    track(other);

    t.enqueue_task = counting_enqueue;
    t.finish_task = counting_finish;
    t.user_context = NULL;
    t.worker_count = 2;

#define STEP(world, dt, tasks, out) mpm_world_step_tasks((world), R(dt), (tasks), (out))
    refused("step_tasks: NULL world", MPM_STATUS_NULL_POINTER,
            STEP(NULL, 1.0 / 600, &t, OUT(MpmStepReport)));
    refused("step_tasks: NULL task system", MPM_STATUS_NULL_POINTER,
            STEP(w, 1.0 / 600, NULL, OUT(MpmStepReport)));
    refused("step_tasks: NULL report", MPM_STATUS_NULL_POINTER, STEP(w, 1.0 / 600, &t, NULL));
    bad = t;
    bad.enqueue_task = NULL;
    refused("step_tasks: NULL enqueue_task", MPM_STATUS_NULL_POINTER,
            STEP(w, 1.0 / 600, &bad, OUT(MpmStepReport)));
    bad = t;
    bad.finish_task = NULL;
    refused("step_tasks: NULL finish_task", MPM_STATUS_NULL_POINTER,
            STEP(w, 1.0 / 600, &bad, OUT(MpmStepReport)));
    bad = t;
    bad.worker_count = 0;
    refused("step_tasks: worker_count 0", MPM_STATUS_INVALID_LIMIT,
            STEP(w, 1.0 / 600, &bad, OUT(MpmStepReport)));
    bad.worker_count = def.workers + 1;
    refused("step_tasks: worker_count past the definition's workers", MPM_STATUS_INVALID_LIMIT,
            STEP(w, 1.0 / 600, &bad, OUT(MpmStepReport)));
    bad.worker_count = UINT32_MAX;
    refused("step_tasks: worker_count UINT32_MAX", MPM_STATUS_INVALID_LIMIT,
            STEP(w, 1.0 / 600, &bad, OUT(MpmStepReport)));
    refused("step_tasks: dt 0", MPM_STATUS_INVALID_TIME_STEP,
            STEP(w, 0.0, &t, OUT(MpmStepReport)));
    refused("step_tasks: dt NaN", MPM_STATUS_INVALID_TIME_STEP,
            mpm_world_step_tasks(w, (mpm_real)NAN, &t, OUT(MpmStepReport)));
    refused_after_scan("step_tasks: dt past max_substeps", MPM_STATUS_SUBSTEP_LIMIT,
            STEP(w, 10.0, &t, OUT(MpmStepReport)));
    refused("step_tasks: report inside the world", MPM_STATUS_OVERLAPPING_MEMORY,
            STEP(w, 1.0 / 600, &t, (MpmStepReport *)(void *)((unsigned char *)w + 64)));
    if (posix_memalign(&not_world, 64, 4096) != 0) {
        fail("posix_memalign", "out of memory");
    }
    memset(not_world, 0, 4096);
    refused("step_tasks: not a world", MPM_STATUS_NOT_A_WORLD,
            STEP((MpmWorld *)not_world, 1.0 / 600, &t, OUT(MpmStepReport)));
    free(not_world);
#undef STEP

    /* Accepted: the definition's workers exactly, and the struct read once (changing it in a
     * callback would change nothing). */
    bad = t;
    bad.worker_count = def.workers;
    out_reset();
    accepted_check("step_tasks: worker_count equal to the definition's workers", 1,
                   mpm_world_step_tasks(w, R(1.0 / 600), &bad, OUT(MpmStepReport)));
    expect_true("step_tasks: the report is written", !out_untouched());
    expect_true("step_tasks: finish is not called for a task that enqueue ran", g_finishes == 0);
    untrack(other);
    untrack(w);
    free(other);
    free(w);
}

/* ---- hostile hosts --------------------------------------------------------------------- */

static void hostile(void) {
    Scene s = plane2d();
    uint64_t want[FRAMES];
    int mode;
    reference(&s, want);
    for (mode = HOST_PAST_END; mode < HOST_COUNT; mode++) {
        Host h;
        MpmTaskSystem t;
        MpmWorld *w = seed(&s);
        MpmWorld *opened = NULL;
        MpmStepReport r;
        MpmStatus st;
        char name[160];
        size_t bytes = 0;
        unsigned char *snapshot;
        int contract;
        memset(&h, 0, sizeof h);
        h.mode = (HostMode)mode;
        h.worker_count = 2;
        t = host_system(&h);
        must("mpm_world_bytes", mpm_world_bytes(w, &bytes));
        snapshot = (unsigned char *)malloc(bytes);
        if (snapshot == NULL) {
            fail("malloc", "out of memory");
        }
        memcpy(snapshot, w, bytes);
        out_reset();
        st = mpm_world_step_tasks(w, R(1.0 / 60), &t, OUT(MpmStepReport));
        contract = mode == HOST_SAME_COUNT ? h.twisted > 0 : h.tasks > 0;
        if (!contract) {
            snprintf(name, sizeof name,
                     "a host whose tasks break the contract (%s): the step handed it no task "
                     "and succeeded",
                     HOST_NAMES[mode]);
            expect_true(name, st == MPM_STATUS_OK && !out_untouched());
        } else {
            snprintf(name, sizeof name,
                     "a host whose tasks break the contract (%s, %lu tasks): "
                     "MPM_STATUS_TASK_CONTRACT without a report",
                     HOST_NAMES[mode], h.tasks);
            expect_true(name, st == MPM_STATUS_TASK_CONTRACT && out_untouched());
        }
        /* The promise after MPM_STATUS_TASK_CONTRACT: the snapshot restores the world, which
         * then steps as a world that never met the host. */
        memcpy(w, snapshot, bytes);
        must("mpm_world_open", mpm_world_open(w, bytes, &opened));
        must("mpm_world_step", mpm_world_step(opened, R(1.0 / 60), &r));
        snprintf(name, sizeof name,
                 "after a host whose tasks break the contract (%s): the snapshot taken before "
                 "opens and steps as the world it was",
                 HOST_NAMES[mode]);
        expect_true(name, opened == w && state_hash(opened, &r) == want[0]);
        free(snapshot);
        free(w);
    }
}

int main(void) {
    Scene scenes[3];
    size_t i;
    const char *simd = getenv("MPM_GIMP_SIMD");
    if (simd != NULL && strcmp(simd, "baseline") == 0) {
        mpm_simd_use_baseline_only();
    }
    scenes[0] = plane2d();
    scenes[1] = effects2d();
    scenes[2] = space3d();
    for (i = 0; i < 3; i++) {
        same_state_everywhere(&scenes[i]);
    }
    misuse();
    hostile();
    printf("all %lu tasks checks passed\n", g_checks);
    return 0;
}
