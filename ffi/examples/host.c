/*
 * A C99 host of libmpm_gimp: an elastic block dropped on a sticky floor in a 1 m x 1 m box,
 * stepped for one second in a fixed 60 Hz frame loop. The world lives in a static array this
 * program owns; the library never allocates. The steps run on the host's task system, a pool
 * of worker threads (a mutex and two condition variables around a queue of ranges), to which
 * mpm_world_step_tasks hands each parallel pass of a step as a task over a range of items. A
 * host with no threads of its own steps with mpm_world_step instead; the results are the
 * same, bit for bit.
 *
 * Build against the single-precision static library (from the repository root):
 *   cargo build --release -p mpm-gimp-ffi
 *   gcc -std=c99 -Wall -Wextra -Werror -pedantic -I ffi/include ffi/examples/host.c \
 *       target/release/libmpm_gimp.a -lpthread -ldl -lm -o host
 * For the double-precision library, built beside it (cargo build --release -p mpm-gimp-ffi
 * --features f64 --target-dir target/f64), add -DMPM_GIMP_F64 and link
 * target/f64/release/libmpm_gimp.a. Against an installed library: ffi/README.md.
 *
 * Output, one line at t = 0 and every 10 frames (the last one at t = 1 s):
 *   t=<s> com_y=<m> kinetic=<J> strain=<J> potential=<J> total=<J>
 * then one line
 *   done frames=<n> substeps=<n> particles=<n> frozen=<n> escaped=<n> lowest_y=<m>
 * Energies are per metre of thickness (the 2D world is plane strain). On failure the failing
 * call and mpm_status_string() go to stderr and the exit status is 1.
 */
/* pthreads under -std=c99. */
#define _POSIX_C_SOURCE 200809L

#include <pthread.h>
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

/* ---- the worker pool: the host's task system ------------------------------------------ */

#define WORKERS 4

/* One range of a task: items start .. end. */
typedef struct Job {
    MpmTaskCallback *task;
    void *context;
    uint32_t start, end;
} Job;

typedef struct Pool Pool;

typedef struct Worker {
    Pool *pool;
    uint32_t index; /* the worker index every range this thread runs gets */
    pthread_t thread;
} Worker;

struct Pool {
    pthread_mutex_t lock;
    pthread_cond_t work; /* jobs were queued, or the pool stops */
    pthread_cond_t idle; /* the last job of the task has returned */
    Job jobs[WORKERS];   /* one task at a time: at most one range per worker */
    int queued;          /* jobs not yet taken */
    int pending;         /* jobs not yet returned */
    int stop;
    Worker workers[WORKERS];
};

static void *worker_main(void *arg)
{
    Worker *self = (Worker *)arg;
    Pool *pool = self->pool;
    pthread_mutex_lock(&pool->lock);
    for (;;) {
        while (pool->queued == 0 && !pool->stop) pthread_cond_wait(&pool->work, &pool->lock);
        if (pool->queued == 0) break; /* stopping */
        Job job = pool->jobs[--pool->queued];
        pthread_mutex_unlock(&pool->lock);
        job.task(job.start, job.end, self->index, job.context);
        pthread_mutex_lock(&pool->lock);
        if (--pool->pending == 0) pthread_cond_signal(&pool->idle);
    }
    pthread_mutex_unlock(&pool->lock);
    return NULL;
}

/* MpmEnqueueTaskCallback: cuts the items into at most WORKERS ranges of at least min_range
 * items and queues them; a task too small to share runs here, on the calling thread. */
static void *pool_enqueue(MpmTaskCallback *task, uint32_t item_count, uint32_t min_range,
                          void *task_context, void *user_context)
{
    Pool *pool = (Pool *)user_context;
    uint32_t ranges = item_count / (min_range > 0 ? min_range : 1);
    if (ranges > WORKERS) ranges = WORKERS;
    if (ranges <= 1) {
        task(0, item_count, 0, task_context);
        return NULL;
    }
    pthread_mutex_lock(&pool->lock);
    for (uint32_t i = 0; i < ranges; ++i) {
        Job job;
        job.task = task;
        job.context = task_context;
        job.start = (uint32_t)((uint64_t)item_count * i / ranges);
        job.end = (uint32_t)((uint64_t)item_count * (i + 1) / ranges);
        pool->jobs[pool->queued++] = job;
    }
    pool->pending = (int)ranges;
    pthread_cond_broadcast(&pool->work);
    pthread_mutex_unlock(&pool->lock);
    return pool;
}

/* MpmFinishTaskCallback: waits until every range has returned. The mutex makes what the
 * workers wrote visible here. */
static void pool_finish(void *user_task, void *user_context)
{
    Pool *pool = (Pool *)user_task;
    (void)user_context;
    pthread_mutex_lock(&pool->lock);
    while (pool->pending > 0) pthread_cond_wait(&pool->idle, &pool->lock);
    pthread_mutex_unlock(&pool->lock);
}

/* Starts the pool's threads (pool zeroed). */
static void pool_start(Pool *pool)
{
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->work, NULL);
    pthread_cond_init(&pool->idle, NULL);
    for (uint32_t i = 0; i < WORKERS; ++i) {
        pool->workers[i].pool = pool;
        pool->workers[i].index = i;
        if (pthread_create(&pool->workers[i].thread, NULL, worker_main, &pool->workers[i]) != 0) {
            fprintf(stderr, "host: pthread_create failed\n");
            exit(EXIT_FAILURE);
        }
    }
}

/* Stops the threads once the queue is empty and waits for them. */
static void pool_stop(Pool *pool)
{
    pthread_mutex_lock(&pool->lock);
    pool->stop = 1;
    pthread_cond_broadcast(&pool->work);
    pthread_mutex_unlock(&pool->lock);
    for (int i = 0; i < WORKERS; ++i) pthread_join(pool->workers[i].thread, NULL);
    pthread_cond_destroy(&pool->idle);
    pthread_cond_destroy(&pool->work);
    pthread_mutex_destroy(&pool->lock);
}

/* ---- the simulation -------------------------------------------------------------------- */

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
    /* The world's memory holds scratch for this many workers. */
    def.workers = WORKERS;

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

    static Pool pool;
    pool_start(&pool);
    MpmTaskSystem tasks;
    tasks.enqueue_task = pool_enqueue;
    tasks.finish_task = pool_finish;
    tasks.user_context = &pool;
    tasks.worker_count = WORKERS;

    /* The kernel splits each frame into equal substeps no longer than the stable one. */
    const mpm_real frame_dt = (mpm_real)(1.0 / FRAMES);
    unsigned long substeps = 0, frozen = 0, escaped = 0;
    report(world);
    for (int frame = 1; frame <= FRAMES; ++frame) {
        MpmStepReport step;
        check(mpm_world_step_tasks(world, frame_dt, &tasks, &step), "mpm_world_step_tasks");
        substeps += step.substeps;
        frozen += step.frozen;
        escaped += step.escaped;
        if (frame % REPORT_EVERY == 0 || frame == FRAMES) report(world);
    }
    pool_stop(&pool);

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
