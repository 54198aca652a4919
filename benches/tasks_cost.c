/*
 * What a step costs through the C interface on a host's pool of threads
 * (mpm_world_step_tasks), in nanoseconds per particle-step: step_cost's 2D scene (a block of
 * 256 x 128 cells at 2 particles per cell per axis, 131,072 particles, neo-Hookean, falling at
 * 0.1 m/s in a 260 x 132 grid of 1 cm cells), stepped by the library's C adapter of the
 * host's task system. What the adapter adds to a step (its checks of the ranges the host
 * runs) shows against a build without them.
 *
 * Build against a static library (from the repository root):
 *   cargo build --release -p mpm-gimp-ffi
 *   gcc -std=c99 -O2 -I ffi/include benches/tasks_cost.c target/release/libmpm_gimp.a \
 *       -lpthread -ldl -lm -o target/release/tasks_cost
 * Options: --threads N (the pool's threads and the world's workers, 1 to 16, default 2),
 * --shrink N (1, 2, 4 or 8: the block's cells per axis divided by N, the grid with it, N^2
 * times fewer particles, where the adapter's cost per pass weighs more), --runs N (default 7,
 * at least 3), --steps N (default 10). Each step is one substep (dt = mpm_world_stable_dt);
 * 3 untimed steps, then the runs; only mpm_world_step_tasks is timed, in wall time.
 *
 * Output: one JSON line on stdout, as step_cost's, with "ns_per_particle_step" (the median of
 * the runs) and "state_hash" (FNV-1a of the particle columns after the last step), so that
 * benches/compare.sh compares two builds of it:
 *   bash benches/compare.sh 9 ./tasks_cost_before target/release/tasks_cost -- --threads 2
 * Errors: a message on stderr and exit status 1 (2 for a bad option).
 */
/* pthreads and clock_gettime under -std=c99. */
#define _POSIX_C_SOURCE 200809L

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mpm_gimp.h"

#define MAX_THREADS 16

/* ---- the host's pool: persistent threads, one range per thread and task ------------- */

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
    uint32_t threads;
    MpmTaskCallback *task;
    void *context;
    uint32_t items, ranges, next, done;
    unsigned long generation; /* tasks queued so far */
    int stop;
    Worker workers[MAX_THREADS];
};

static void *worker_main(void *arg) {
    Worker *self = (Worker *)arg;
    Pool *p = self->pool;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        uint32_t k, start, end;
        while ((p->task == NULL || p->next == p->ranges) && !p->stop) {
            pthread_cond_wait(&p->work, &p->lock);
        }
        if (p->stop) {
            break;
        }
        k = p->next++;
        start = (uint32_t)((uint64_t)p->items * k / p->ranges);
        end = (uint32_t)((uint64_t)p->items * (k + 1) / p->ranges);
        pthread_mutex_unlock(&p->lock);
        p->task(start, end, self->index, p->context);
        pthread_mutex_lock(&p->lock);
        if (++p->done == p->ranges) {
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
    if (ranges > p->threads) {
        ranges = p->threads;
    }
    if (ranges <= 1) {
        task(0, item_count, 0, task_context);
        return NULL;
    }
    pthread_mutex_lock(&p->lock);
    p->task = task;
    p->context = task_context;
    p->items = item_count;
    p->ranges = ranges;
    p->next = 0;
    p->done = 0;
    p->generation++;
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

static int pool_start(Pool *p, uint32_t threads) {
    uint32_t i;
    memset(p, 0, sizeof *p);
    p->threads = threads;
    if (pthread_mutex_init(&p->lock, NULL) != 0 || pthread_cond_init(&p->work, NULL) != 0 ||
        pthread_cond_init(&p->idle, NULL) != 0) {
        return 0;
    }
    for (i = 0; i < threads; i++) {
        p->workers[i].pool = p;
        p->workers[i].index = i;
        if (pthread_create(&p->workers[i].thread, NULL, worker_main, &p->workers[i]) != 0) {
            return 0;
        }
    }
    return 1;
}

static void pool_stop(Pool *p) {
    uint32_t i;
    pthread_mutex_lock(&p->lock);
    p->stop = 1;
    pthread_cond_broadcast(&p->work);
    pthread_mutex_unlock(&p->lock);
    for (i = 0; i < p->threads; i++) {
        pthread_join(p->workers[i].thread, NULL);
    }
}

/* ---- the scene and its timing ------------------------------------------------------- */

static void must(const char *what, MpmStatus s) {
    if (s != MPM_STATUS_OK) {
        fprintf(stderr, "%s: %s\n", what, mpm_status_string(s));
        exit(1);
    }
}

static MpmVec3 v3(double x, double y, double z) {
    MpmVec3 v;
    v.x = (mpm_real)x;
    v.y = (mpm_real)y;
    v.z = (mpm_real)z;
    return v;
}

static double now_ns(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec * 1e9 + (double)t.tv_nsec;
}

static int by_value(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static uint64_t fnv(uint64_t h, const void *data, size_t n) {
    const unsigned char *c = (const unsigned char *)data;
    size_t i;
    for (i = 0; i < n; i++) {
        h ^= c[i];
        h *= UINT64_C(0x100000001b3);
    }
    return h;
}

static unsigned parse(const char *v, unsigned min, unsigned max) {
    char *end = NULL;
    unsigned long n = v != NULL ? strtoul(v, &end, 10) : 0;
    if (v == NULL || *end != '\0' || n < min || n > max) {
        fprintf(stderr, "usage: tasks_cost [--threads 1..16] [--shrink 1|2|4|8] [--runs N >= 3] "
                        "[--steps N >= 1]\n");
        exit(2);
    }
    return (unsigned)n;
}

int main(int argc, char **argv) {
    unsigned threads = 2, shrink = 1, runs = 7, steps = 10, i, r, s;
    MpmWorldDef def = mpm_world_def_default();
    MpmMemoryRequirements req;
    MpmMaterialDef m = mpm_material_def_default();
    MpmTaskSystem tasks;
    MpmParticlesView view;
    MpmIdRange ids;
    MpmWorld *world = NULL;
    void *memory = NULL;
    Pool pool;
    double *per_run;
    double spacing, lo[2], hi[2];
    uint64_t hash = UINT64_C(0xcbf29ce484222325);
    uint32_t id = 0, block[2];
    int a;
    for (a = 1; a < argc; a++) {
        const char *v = a + 1 < argc ? argv[a + 1] : NULL;
        if (strcmp(argv[a], "--threads") == 0) {
            threads = parse(v, 1, MAX_THREADS);
        } else if (strcmp(argv[a], "--shrink") == 0) {
            shrink = parse(v, 1, 8);
            if (shrink & (shrink - 1)) {
                parse(NULL, 0, 0);
            }
        } else if (strcmp(argv[a], "--runs") == 0) {
            runs = parse(v, 3, 1000);
        } else if (strcmp(argv[a], "--steps") == 0) {
            steps = parse(v, 1, 100000);
        } else {
            parse(NULL, 0, 0);
        }
        a++;
    }
    block[0] = 256 / shrink;
    block[1] = 128 / shrink;
    def.cells[0] = block[0] + 4;
    def.cells[1] = block[1] + 4;
    def.cell_size = (mpm_real)0.01;
    def.particles_per_cell = 2;
    def.particle_capacity = block[0] * block[1] * 4;
    def.material_capacity = 1;
    def.workers = threads;
    must("mpm_memory_requirements", mpm_memory_requirements(&def, &req));
    if (posix_memalign(&memory, req.align, req.bytes) != 0) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    must("mpm_world_init", mpm_world_init(&def, memory, req.bytes, &world));
    must("mpm_world_add_material", mpm_world_add_material(world, &m, &id));
    /* A quarter of the particle spacing inside the block's faces, as step_cost's. */
    spacing = 0.01 / 2;
    for (i = 0; i < 2; i++) {
        lo[i] = 2 * 0.01 + 0.25 * spacing;
        hi[i] = (2 + block[i]) * 0.01 - 0.25 * spacing;
    }
    must("mpm_world_fill_box", mpm_world_fill_box(world, v3(lo[0], lo[1], 0), v3(hi[0], hi[1], 0),
                                                  id, v3(0, -0.1, 0), &ids));
    if (!pool_start(&pool, threads)) {
        fprintf(stderr, "the pool did not start\n");
        return 1;
    }
    tasks.enqueue_task = pool_enqueue;
    tasks.finish_task = pool_finish;
    tasks.user_context = &pool;
    tasks.worker_count = threads;
    per_run = (double *)malloc(runs * sizeof *per_run);
    if (per_run == NULL) {
        fprintf(stderr, "out of memory\n");
        return 1;
    }
    for (r = 0; r < runs + 1; r++) {
        unsigned n = r == 0 ? 3 : steps;
        double total = 0;
        for (s = 0; s < n; s++) {
            mpm_real dt;
            MpmStepReport report;
            double t0;
            must("mpm_world_stable_dt", mpm_world_stable_dt(world, &dt));
            t0 = now_ns();
            must("mpm_world_step_tasks", mpm_world_step_tasks(world, dt, &tasks, &report));
            total += now_ns() - t0;
            if (report.substeps != 1 || report.frozen != 0) {
                fprintf(stderr, "a step took %u substeps and froze %u particles\n",
                        (unsigned)report.substeps, (unsigned)report.frozen);
                return 1;
            }
        }
        if (r > 0) {
            per_run[r - 1] = total / ((double)n * (double)ids.count);
        }
    }
    pool_stop(&pool);
    qsort(per_run, runs, sizeof *per_run, by_value);
    must("mpm_world_particles", mpm_world_particles(world, &view));
    for (i = 0; i < 2; i++) {
        hash = fnv(hash, view.position[i], view.count * sizeof(mpm_real));
        hash = fnv(hash, view.velocity[i], view.count * sizeof(mpm_real));
    }
    printf("{\"threads\":%u,\"particles\":%u,\"runs\":%u,\"steps\":%u,"
           "\"ns_per_particle_step\":%.3f,\"min_ns_per_particle_step\":%.3f,"
           "\"state_hash\":\"%016llx\"}\n",
           threads, (unsigned)ids.count, runs, steps, per_run[runs / 2], per_run[0],
           (unsigned long long)hash);
    free(per_run);
    free(memory);
    return 0;
}
