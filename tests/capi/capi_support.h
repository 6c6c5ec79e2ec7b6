// Helpers of the C API's tests (capi_create_test.cpp, capi_world_test.cpp): a world
// destroyed with its scope, the errors and arrays read back through the C functions, and
// the C++ twin of the default world.
#pragma once

#include <metariver/metariver.h>
#include <metariver/scene.h>

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <unistd.h>

namespace capi_test {

constexpr float kDt = 1.0f / 60.0f;

/// A world destroyed at the end of the scope.
struct World {
    mr_world* w = nullptr;
    mr_error error{};
    mr_status status = MR_OK;
    explicit World(const mr_world_desc& d) { status = mr_world_create(&d, &w, &error); }
    World() : World(mr_world_desc_default()) {}
    ~World() { mr_world_destroy(w); }
    World(const World&) = delete;
    World& operator=(const World&) = delete;
    void step(int frames) {
        for (int f = 0; f < frames; ++f) ASSERT_EQ(mr_world_step(w, kDt), MR_OK) << mr_world_last_error(w);
    }
    mr_stats stats() const {
        mr_stats s{};
        EXPECT_EQ(mr_world_stats(w, &s), MR_OK);
        return s;
    }
    std::string last_error() const { return mr_world_last_error(w); }
};

inline bool contains(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

/// The error of creating a world from `d` (expecting it to fail with `code`).
inline std::string create_error(const mr_world_desc& d, mr_status code) {
    World world(d);
    EXPECT_EQ(world.status, code) << world.error.message;
    EXPECT_EQ(world.error.code, code);
    EXPECT_EQ(world.w, nullptr) << "a failed create hands out no world";
    return world.error.message;
}

/// The terrain's size and range through mr_world_terrain.
inline mr_terrain_info terrain_info(const World& world) {
    mr_terrain_info t{};
    EXPECT_EQ(mr_world_terrain(world.w, &t), MR_OK);
    return t;
}

/// The terrain's heights through mr_world_copy_terrain_heights.
inline std::vector<float> terrain_heights(const World& world) {
    const mr_terrain_info t = terrain_info(world);
    std::vector<float> h(static_cast<size_t>(t.columns) * t.rows);
    EXPECT_EQ(mr_world_copy_terrain_heights(world.w, h.data(), h.size()), MR_OK);
    return h;
}

/// Writes `text` to a file of this process in the temporary folder; returns its path.
inline std::string temp_file(const std::string& name, const std::string& text) {
    const auto path =
        std::filesystem::temp_directory_path() / ("capi_test_" + std::to_string(::getpid()) + "_" + name);
    std::ofstream(path, std::ios::binary) << text;
    return path.string();
}

/// A ramp along +z (row k: k / (rows - 1)) with a step along +x, in the caller's order.
inline std::vector<float> ramp(int columns, int rows) {
    std::vector<float> h(static_cast<size_t>(columns) * rows);
    for (int k = 0; k < rows; ++k)
        for (int c = 0; c < columns; ++c) h[k * columns + c] = 0.8f * k / (rows - 1) + (c >= columns / 2 ? 0.2f : 0.0f);
    return h;
}

/// The default world's C++ twin: a Simulation of the default scene stepped `frames` frames.
inline std::unique_ptr<mr::Simulation> twin(int frames) {
    auto sim = mr::Simulation::create(mr::default_scene());
    EXPECT_TRUE(sim.ok()) << sim.error().message;
    if (!sim.ok()) return nullptr;
    for (int f = 0; f < frames; ++f) sim.value()->step(kDt);
    return std::move(sim.value());
}

inline std::vector<float> copy_positions(const World& world) {
    size_t count = 0;
    EXPECT_EQ(mr_world_copy_particles(world.w, nullptr, nullptr, 0, &count), MR_OK);
    std::vector<float> p(3 * count);
    size_t again = 0;
    EXPECT_EQ(mr_world_copy_particles(world.w, p.data(), nullptr, count, &again), MR_OK);
    EXPECT_EQ(again, count);
    return p;
}

}  // namespace capi_test
