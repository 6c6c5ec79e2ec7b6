// No heap allocation in a steady-state frame of the fast pipeline: every global
// operator new is counted (this executable replaces it), and once a scene has settled
// its frames must allocate nothing: per-frame scratch is reused, not rebuilt.
#include <metariver/scene.h>
#include <metariver/workloads.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <new>
#include <vector>

namespace {
std::atomic<bool> g_counting{false};
std::atomic<size_t> g_allocations{0};

void* counted_alloc(std::size_t n, std::size_t align = 0) {
    if (g_counting.load(std::memory_order_relaxed)) g_allocations.fetch_add(1, std::memory_order_relaxed);
    void* p = align ? std::aligned_alloc(align, (n + align - 1) / align * align) : std::malloc(n ? n : 1);
    if (!p) throw std::bad_alloc();
    return p;
}
void* counted_alloc_nothrow(std::size_t n, std::size_t align = 0) noexcept {
    try {
        return counted_alloc(n, align);
    } catch (const std::bad_alloc&) {
        return nullptr;
    }
}
}  // namespace

// Every replaceable form (C++17 [new.delete]): a form left out keeps the library's
// version, and memory it hands out would reach a replaced one (std::stable_sort's
// temporary buffer comes from the nothrow form and goes back through the plain
// delete: an alloc-dealloc mismatch under AddressSanitizer, and an allocation the
// count would miss).
void* operator new(std::size_t n) { return counted_alloc(n); }
void* operator new[](std::size_t n) { return counted_alloc(n); }
void* operator new(std::size_t n, std::align_val_t a) { return counted_alloc(n, static_cast<size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return counted_alloc(n, static_cast<size_t>(a)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return counted_alloc_nothrow(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return counted_alloc_nothrow(n); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return counted_alloc_nothrow(n, static_cast<size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
    return counted_alloc_nothrow(n, static_cast<size_t>(a));
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }

namespace mr {
namespace {

TEST(Allocations, CountingWorks) {
    g_allocations = 0;
    g_counting = true;
    auto* v = new std::vector<int>(100);
    g_counting = false;
    delete v;
    EXPECT_GE(g_allocations.load(), 2u) << "the counter must see allocations, or the next test proves nothing";
}

TEST(Allocations, CountingSeesTheNothrowFormStableSortUses) {
    std::vector<int> v(1000);
    for (size_t i = 0; i < v.size(); ++i) v[i] = static_cast<int>((i * 7919) % 1000);
    g_allocations = 0;
    g_counting = true;
    std::stable_sort(v.begin(), v.end());  // its temporary buffer: operator new(n, std::nothrow)
    g_counting = false;
    EXPECT_GE(g_allocations.load(), 1u) << "std::stable_sort's buffer was not counted";
    EXPECT_TRUE(std::is_sorted(v.begin(), v.end()));
}

void expect_steady_state_allocates_nothing(bool smoothing) {
    // Water settled in a closed bowl: a steady state (no new regions of the field).
    SceneDef d = river_scene(3000);
    if (smoothing) d.smoothing = default_scene().smoothing;  // issue 11: the default river's
    d.source = {.kind = TerrainSource::Bowl, .heightmap = {}, .width = 33, .height = 33, .seed = 1};
    d.terrain.height_scale = 7.0f;
    d.spawn.auto_center = false;
    d.spawn.center = Vec3(16, 6, 16);
    d.spawn.half_extent = Vec3(3, 1, 3);
    d.spawn.initial_velocity = Vec3(0.0f);
    d.collision.damping = 0.3f;
    d.field.bounds = FieldBounds::Terrain;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int f = 0; f < 400; ++f) s.step(1.0f / 60.0f);
    ASSERT_GT(s.surface().triangle_count(), 100u);
    g_allocations = 0;
    g_counting = true;
    for (int f = 0; f < 30; ++f) s.step(1.0f / 60.0f);
    g_counting = false;
    EXPECT_EQ(g_allocations.load(), 0u) << "allocations in 30 steady-state frames";
    EXPECT_GT(s.surface().triangle_count(), 100u);
    if (smoothing) {
        EXPECT_GT(s.smoothing_stats().moving, 100u) << "the smoothing ran";
    }
}

TEST(Allocations, SteadyStateFramesOfTheFastPipelineAllocateNothing) { expect_steady_state_allocates_nothing(false); }

TEST(Allocations, SteadyStateFramesWithTheSurfaceSmoothedAllocateNothing) { expect_steady_state_allocates_nothing(true); }

}  // namespace
}  // namespace mr
