// Shared by the render test files: the headless OpenGL context (gl_test_context.h), the
// small deterministic valley scene, and an image comparison.
#pragma once

#include "gl_test_context.h"

#include <metariver/render.h>
#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

namespace mr::test {

/// A small deterministic scene: a reduced procedural valley with the paper's own
/// physics. Built on the paper-bowl preset (the paper's fixed parameters), not on
/// default_scene(), so the golden images follow the renderer, not the default scene's tuning.
inline SceneDef small_valley() {
    auto p = preset("paper-bowl");
    EXPECT_TRUE(p.ok());
    SceneDef d = p.ok() ? p.value() : SceneDef{};
    d.name = "render-test-valley";
    d.source = {.kind = TerrainSource::Valley, .heightmap = {}, .width = 33, .height = 49, .seed = 7};
    d.terrain.height_scale = 12.0f;
    d.spawn.count = 120;
    d.spawn.interval = 1;
    d.spawn.auto_center = true;
    d.spawn.auto_height = 1.5f;
    d.spawn.half_extent = Vec3(1.5f, 0.5f, 1.5f);
    d.springs.stiffness = 4.0f;
    d.springs.min_distance = 1.0f;
    d.springs.max_distance = 0.5f;
    d.collision.mode = CollisionMode::Robust;
    d.collision.damping = 0.003f;
    d.collision.offset = 0.02f;
    d.field.resolution = 1.5f;
    d.field.bounds_offset = 2.0f;
    d.field.threshold = 0.08f;
    return d;
}

/// The simulation of `def` after `frames` frames of 1/60 s, or null after a test failure
/// that names create()'s error (callers ASSERT_TRUE on it).
inline std::unique_ptr<Simulation> stepped(const SceneDef& def, int frames) {
    auto sim = Simulation::create(def);
    EXPECT_TRUE(sim.ok()) << (sim.ok() ? "" : sim.error().message);
    if (!sim.ok()) return nullptr;
    for (int i = 0; i < frames; ++i) sim.value()->step(1.0f / 60.0f);
    return std::move(sim.value());
}

/// Pixels where two images differ by more than `by` in some channel.
inline size_t pixels_differing(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, int by) {
    size_t n = 0;
    for (size_t p = 0; p + 2 < a.size() && p + 2 < b.size(); p += 3) {
        bool d = false;
        for (int c = 0; c < 3; ++c) d |= std::abs(int(a[p + c]) - int(b[p + c])) > by;
        n += d;
    }
    return n;
}

}  // namespace mr::test
