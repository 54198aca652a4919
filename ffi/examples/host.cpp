/*
 * A C++17 host of libmpm_gimp: the scene of host.c (an elastic block dropped on a sticky floor
 * in a 1 m x 1 m box, one second at 60 frames per second) with the world's memory from the
 * system allocator, owned by an RAII wrapper, stepped on a pool of std::threads (the host's
 * task system, as in host.c). Same output format as host.c.
 *
 * Build against the single-precision static library (from the repository root):
 *   cargo build --release -p mpm-gimp-ffi
 *   g++ -std=c++17 -Wall -Wextra -Werror -pedantic -I ffi/include ffi/examples/host.cpp \
 *       target/release/libmpm_gimp.a -lpthread -ldl -lm -o host_cpp
 * For the double-precision library, built beside it (cargo build --release -p mpm-gimp-ffi
 * --features f64 --target-dir target/f64), add -DMPM_GIMP_F64 and link
 * target/f64/release/libmpm_gimp.a. Against an installed library: ffi/README.md and
 * ffi/examples/cmake.
 */
#include <algorithm>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <memory>
#include <mutex>
#include <new>
#include <string_view>
#include <thread>
#include <vector>

#include "mpm_gimp.h"

namespace {

// The scene; see host.c.
constexpr std::uint32_t kCells = 32;
constexpr std::uint32_t kBlockParticles = 16 * 16;
constexpr std::uint32_t kParticleCapacity = 2 * kBlockParticles;
constexpr int kFrames = 60;
constexpr int kReportEvery = 10;

// A call that did not answer MPM_STATUS_OK.
struct MpmFailure {
    const char* call;
    MpmStatus status;
};

void check(MpmStatus status, const char* call) {
    if (status != MPM_STATUS_OK) throw MpmFailure{call, status};
}

constexpr MpmVec3 vec2(double x, double y) {
    return MpmVec3{static_cast<mpm_real>(x), static_cast<mpm_real>(y), mpm_real{0}};
}

// A fixed pool of worker threads: the host's task system (MpmTaskSystem). Each task is cut
// into at most one range per worker, which the threads take from a queue; finish waits until
// every range has returned.
class ThreadPool {
public:
    explicit ThreadPool(std::uint32_t workers) : workers_(workers) {
        for (std::uint32_t i = 0; i < workers; ++i) threads_.emplace_back([this, i] { run(i); });
    }
    ~ThreadPool() {
        {
            // Notified under the lock, here and in enqueue: helgrind calls a notify without
            // it dubious.
            std::lock_guard<std::mutex> lock(mutex_);
            stop_ = true;
            work_.notify_all();
        }
        for (std::thread& t : threads_) t.join();
    }
    ThreadPool(const ThreadPool&) = delete;
    ThreadPool& operator=(const ThreadPool&) = delete;

    MpmTaskSystem task_system() {
        MpmTaskSystem tasks{};
        tasks.enqueue_task = enqueue;
        tasks.finish_task = finish;
        tasks.user_context = this;
        tasks.worker_count = workers_;
        return tasks;
    }

private:
    struct Job {
        MpmTaskCallback* task;
        void* context;
        std::uint32_t start, end;
    };

    // The thread of worker `index`: runs every range it takes with that worker index.
    void run(std::uint32_t index) {
        std::unique_lock<std::mutex> lock(mutex_);
        for (;;) {
            work_.wait(lock, [this] { return !jobs_.empty() || stop_; });
            if (jobs_.empty()) return;  // stopping
            const Job job = jobs_.back();
            jobs_.pop_back();
            lock.unlock();
            job.task(job.start, job.end, index, job.context);
            lock.lock();
            if (--pending_ == 0) idle_.notify_one();
        }
    }

    // MpmEnqueueTaskCallback: at most one range per worker, each of at least min_range items;
    // a task too small to share runs on the calling thread.
    static void* enqueue(MpmTaskCallback* task, std::uint32_t item_count, std::uint32_t min_range,
                         void* task_context, void* user_context) {
        auto* pool = static_cast<ThreadPool*>(user_context);
        const std::uint32_t ranges =
            std::min(pool->workers_, item_count / std::max<std::uint32_t>(min_range, 1));
        if (ranges <= 1) {
            task(0, item_count, 0, task_context);
            return nullptr;
        }
        {
            std::lock_guard<std::mutex> lock(pool->mutex_);
            for (std::uint32_t i = 0; i < ranges; ++i) {
                const auto cut = [&](std::uint32_t k) {
                    return static_cast<std::uint32_t>(std::uint64_t{item_count} * k / ranges);
                };
                pool->jobs_.push_back(Job{task, task_context, cut(i), cut(i + 1)});
            }
            pool->pending_ = ranges;
            pool->work_.notify_all();
        }
        return pool;
    }

    // MpmFinishTaskCallback: waits until every range has returned.
    static void finish(void* user_task, void* /*user_context*/) {
        auto* pool = static_cast<ThreadPool*>(user_task);
        std::unique_lock<std::mutex> lock(pool->mutex_);
        pool->idle_.wait(lock, [pool] { return pool->pending_ == 0; });
    }

    const std::uint32_t workers_;
    std::mutex mutex_;
    std::condition_variable work_;  // jobs were queued, or the pool stops
    std::condition_variable idle_;  // the last range of the task has returned
    std::vector<Job> jobs_;
    std::uint32_t pending_ = 0;  // ranges not yet returned
    bool stop_ = false;
    std::vector<std::thread> threads_;
};

constexpr std::uint32_t kWorkers = 4;

// Frees memory from the aligned operator new with the same alignment.
struct AlignedDelete {
    std::align_val_t align;
    void operator()(void* p) const noexcept { ::operator delete(p, align); }
};

// A world and the memory it lives in; the world ends when the memory is freed.
class World {
public:
    explicit World(const MpmWorldDef& def) {
        MpmMemoryRequirements req{};
        check(mpm_memory_requirements(&def, &req), "mpm_memory_requirements");
        const std::align_val_t align{req.align};
        memory_ = std::unique_ptr<void, AlignedDelete>(::operator new(req.bytes, align),
                                                       AlignedDelete{align});
        check(mpm_world_init(&def, memory_.get(), req.bytes, &world_), "mpm_world_init");
    }
    // One owner per world: a byte copy would be a snapshot, opened with mpm_world_open.
    World(const World&) = delete;
    World& operator=(const World&) = delete;

    std::uint32_t add_material(const MpmMaterialDef& def) {
        std::uint32_t id = 0;
        check(mpm_world_add_material(world_, &def, &id), "mpm_world_add_material");
        return id;
    }

    MpmIdRange fill_box(MpmVec3 min, MpmVec3 max, std::uint32_t material, MpmVec3 velocity) {
        MpmIdRange ids{};
        check(mpm_world_fill_box(world_, min, max, material, velocity, &ids),
              "mpm_world_fill_box");
        return ids;
    }

    // A step on the host's task system (mpm_world_step without one).
    MpmStepReport step(mpm_real dt, const MpmTaskSystem& tasks) {
        MpmStepReport report{};
        check(mpm_world_step_tasks(world_, dt, &tasks, &report), "mpm_world_step_tasks");
        return report;
    }

    MpmDiagnostics diagnostics() const {
        MpmDiagnostics d{};
        check(mpm_world_diagnostics(world_, &d), "mpm_world_diagnostics");
        return d;
    }

    // Positions, x, y per particle (2D).
    std::vector<mpm_real> positions() const {
        std::vector<mpm_real> out(2 * diagnostics().particle_count);
        std::size_t written = 0;
        check(mpm_world_copy_positions(world_, out.data(), out.size(), &written),
              "mpm_world_copy_positions");
        out.resize(written);
        return out;
    }

private:
    std::unique_ptr<void, AlignedDelete> memory_;
    MpmWorld* world_ = nullptr;
};

void report(const World& world) {
    const MpmDiagnostics d = world.diagnostics();
    std::printf("t=%.6f com_y=%.6f kinetic=%.6f strain=%.6f potential=%.6f total=%.6f\n",
                d.time, d.center_of_mass[1], d.kinetic, d.strain, d.potential,
                d.kinetic + d.strain + d.potential);
}

int run() {
    // valgrind 3.19 cannot decode AVX2: MPM_GIMP_SIMD=baseline selects the SSE2 passes,
    // which give bit-identical results.
    const char* simd = std::getenv("MPM_GIMP_SIMD");
    if (simd != nullptr && std::string_view(simd) == "baseline") mpm_simd_use_baseline_only();

    if (mpm_abi_version() != MPM_GIMP_ABI_VERSION) {
        std::fprintf(stderr, "host: library ABI version %lu, header %lu\n",
                     static_cast<unsigned long>(mpm_abi_version()),
                     static_cast<unsigned long>(MPM_GIMP_ABI_VERSION));
        return EXIT_FAILURE;
    }

    MpmWorldDef def = mpm_world_def_default();
    def.cell_size = mpm_real{1} / kCells;
    def.cells[0] = kCells;
    def.cells[1] = kCells;
    def.particle_capacity = kParticleCapacity;
    def.material_capacity = 1;
    def.faces[MPM_FACE_Y_MIN] = MPM_BOUNDARY_STICK;
    def.workers = kWorkers;  // the world's memory holds scratch for this many
    World world(def);

    MpmMaterialDef rubber = mpm_material_def_default();
    rubber.youngs_modulus = static_cast<mpm_real>(1e5);
    const std::uint32_t material = world.add_material(rubber);
    world.fill_box(vec2(0.375, 0.25), vec2(0.625, 0.5), material, vec2(0, 0));

    // The kernel splits each frame into equal substeps no longer than the stable one.
    const auto frame_dt = static_cast<mpm_real>(1.0 / kFrames);
    unsigned long substeps = 0, frozen = 0, escaped = 0;
    ThreadPool pool(kWorkers);
    const MpmTaskSystem tasks = pool.task_system();
    report(world);
    for (int frame = 1; frame <= kFrames; ++frame) {
        const MpmStepReport step = world.step(frame_dt, tasks);
        substeps += step.substeps;
        frozen += step.frozen;
        escaped += step.escaped;
        if (frame % kReportEvery == 0 || frame == kFrames) report(world);
    }

    const std::vector<mpm_real> xy = world.positions();
    if (xy.size() < 2) {
        std::fprintf(stderr, "host: no particle positions to read\n");
        return EXIT_FAILURE;
    }
    mpm_real lowest_y = xy[1];
    for (std::size_t i = 3; i < xy.size(); i += 2) lowest_y = std::min(lowest_y, xy[i]);

    std::printf("done frames=%d substeps=%lu particles=%lu frozen=%lu escaped=%lu "
                "lowest_y=%.6f\n",
                kFrames, substeps, static_cast<unsigned long>(xy.size() / 2), frozen, escaped,
                static_cast<double>(lowest_y));
    return EXIT_SUCCESS;
}

}  // namespace

int main() {
    try {
        return run();
    } catch (const MpmFailure& f) {
        std::fprintf(stderr, "host: %s failed: %s\n", f.call, mpm_status_string(f.status));
    } catch (const std::exception& e) {
        std::fprintf(stderr, "host: %s\n", e.what());
    } catch (...) {
        std::fprintf(stderr, "host: unknown exception\n");
    }
    return EXIT_FAILURE;
}
