// Simulation::set_threads: the caller bounds the threads a Simulation's work uses, and
// the state after a frame does not depend on the count (box2d's test_determinism.c
// across thread counts).
#include <metariver/scene.h>

#include <gtest/gtest.h>
#include <tbb/info.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>
#include <mutex>
#include <set>
#include <thread>

namespace mr {
namespace {

/// What a probe saw inside its step_frame calls.
struct Seen {
    std::mutex mutex;
    std::set<std::thread::id> threads;  ///< threads that ran a chunk of its parallel loop
    int max_concurrency = 0;            ///< tbb::this_task_arena::max_concurrency(), largest seen
};

/// The built-in PBF solver with a probe around its step: the probe reads the arena's
/// concurrency and runs a parallel loop of busy chunks (long enough for every thread the
/// arena allows to take some), recording which threads ran them.
class ProbedSolver final : public Solver {
public:
    ProbedSolver(std::unique_ptr<Solver> inner, std::shared_ptr<Seen> seen)
        : inner_(std::move(inner)), seen_(std::move(seen)) {}
    void step_frame(float frame_dt) override {
        {
            std::lock_guard lock(seen_->mutex);
            seen_->max_concurrency = std::max(seen_->max_concurrency, tbb::this_task_arena::max_concurrency());
        }
        tbb::parallel_for(0, 64, [&](int k) {
            std::atomic<double> sink = 0.0;
            for (int i = 0; i < 20000; ++i) sink = sink + double(i ^ k);  // busy: a chunk takes ~0.1 ms
            std::lock_guard lock(seen_->mutex);
            seen_->threads.insert(std::this_thread::get_id());
        });
        inner_->step_frame(frame_dt);
    }
    const SolverCounters& counters() const override { return inner_->counters(); }
    uint64_t frame() const override { return inner_->frame(); }
    const Particles* water_particles() const override { return inner_->water_particles(); }
    Particles* editable_particles() override { return inner_->editable_particles(); }
    const HeightfieldWater* water_heightfield() const override { return inner_->water_heightfield(); }
    void set_spawn_center(const Vec3& c) override { inner_->set_spawn_center(c); }
    void pour(const Vec3& c, int n) override { inner_->pour(c, n); }
    size_t push(const Vec3& c, float r, const Vec3& v) override { return inner_->push(c, r, v); }
    void place(std::span<const Vec3> p, std::span<const Vec3> v) override { inner_->place(p, v); }
    std::vector<std::string> warnings() const override { return inner_->warnings(); }
    std::span<const Vec3> last_exits() const override { return inner_->last_exits(); }

private:
    std::unique_ptr<Solver> inner_;
    std::shared_ptr<Seen> seen_;
};

/// A registry whose "pbf" is the built-in one wrapped in the probe (same name: the
/// default river sizes and carves itself as with the built-in entry).
SolverRegistry probed_pbf(const std::shared_ptr<Seen>& seen) {
    SolverEntry e = *SolverRegistry::builtin().find(SolverKind::Pbf).value();
    e.create = [inner = e.create, seen](const SceneDef& d, const Terrain& t, const Bvh& b) -> std::unique_ptr<Solver> {
        auto s = inner(d, t, b);
        return s ? std::make_unique<ProbedSolver>(std::move(s), seen) : nullptr;
    };
    SolverRegistry r;
    EXPECT_TRUE(r.add(e).ok());
    return r;
}

/// The default river, smaller (a 33 x 49 valley) so a few hundred frames stay quick.
SceneDef small_river() {
    SceneDef d = default_scene();
    d.source.width = 33;
    d.source.height = 49;
    return d;
}

TEST(SimulationThreads, ACountOutsideItsRangeIsAnErrorNamingThreadsAndChangesNothing) {
    auto sim = Simulation::create(small_river());
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    EXPECT_EQ(s.threads(), 0);  // the default: every core
    ASSERT_TRUE(s.set_threads(3).ok());
    for (const int bad : {-1, Simulation::kMaxThreads + 1, std::numeric_limits<int>::min()}) {
        const Status st = s.set_threads(bad);
        ASSERT_FALSE(st.ok()) << bad;
        EXPECT_NE(st.error().message.find("threads"), std::string::npos) << st.error().message;
        EXPECT_NE(st.error().message.find("1024"), std::string::npos) << st.error().message;
        EXPECT_EQ(s.threads(), 3);
    }
    EXPECT_TRUE(s.set_threads(Simulation::kMaxThreads).ok());
    EXPECT_TRUE(s.set_threads(0).ok());
    EXPECT_EQ(s.threads(), 0);
}

TEST(SimulationThreads, AStepRunsOnAtMostTheThreadsSet) {
    for (const int n : {1, 2, 0}) {
        auto seen = std::make_shared<Seen>();
        auto sim = Simulation::create(small_river(), probed_pbf(seen));
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        Simulation& s = *sim.value();
        ASSERT_TRUE(s.set_threads(n).ok());
        for (int f = 0; f < 5; ++f) s.step(1.0f / 60.0f);
        // Edits run in the arena too (the probe's loop only runs in step_frame; the
        // concurrency the solver's own loops see is the same arena's).
        ASSERT_TRUE(s.push(s.def().spawn.center, 3.0f, Vec3(1.0f, 0.0f, 0.0f)).ok());
        const int every = tbb::info::default_concurrency();
        EXPECT_EQ(seen->max_concurrency, n == 0 ? every : std::min(n, every)) << "threads " << n;  // no more slots than cores
        if (n == 1) {
            EXPECT_EQ(seen->threads.size(), 1u) << "threads 1: only the calling thread works";
        }
        if (n > 0) {
            EXPECT_LE(seen->threads.size(), size_t(n)) << "threads " << n;
        }
        EXPECT_GE(seen->threads.size(), 1u);
    }
}

TEST(SimulationThreads, TheDefaultRiverIsTheSameAtOneTwoAndEveryThread) {
    // 120 frames of the default scene (sized, carved, prefilled, foam on): the particles'
    // state is bit for bit the same whatever the count (the solver's parallel loops
    // gather per particle; its reductions are max and min, exact in any order).
    uint64_t hash[3] = {};
    const int counts[3] = {1, 2, 0};
    for (int k = 0; k < 3; ++k) {
        auto sim = Simulation::create(default_scene());
        ASSERT_TRUE(sim.ok()) << sim.error().message;
        ASSERT_TRUE(sim.value()->set_threads(counts[k]).ok());
        for (int f = 0; f < 120; ++f) sim.value()->step(1.0f / 60.0f);
        ASSERT_GT(sim.value()->particles().active_count(), 0u);
        hash[k] = sim.value()->state_hash();
    }
    EXPECT_EQ(hash[0], hash[1]) << "threads 1 vs 2";
    EXPECT_EQ(hash[0], hash[2]) << "threads 1 vs every core";
}

}  // namespace
}  // namespace mr
