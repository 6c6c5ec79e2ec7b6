// Test support for the export tests: a closed sphere from marching cubes, a small
// terrain, particles with ids, velocities and birth frames, a temporary folder per
// test (CliFixture's), and a way to run outside readers (programs) and capture what
// they print.
#pragma once

#include "cli_fixture.h"

#include <metariver/export.h>
#include <metariver/field.h>
#include <metariver/surface.h>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <unistd.h>

namespace mr::test {

struct Sphere {
    SurfaceMesh mesh;
    Vec3 center{0.0f};
    float radius = 0.0f;
};

/// Marching cubes of the field radius - |p - center| at `spacing`: closed, outward normals.
inline Sphere sphere_mesh(float radius, float spacing) {
    Sphere s;
    s.center = Vec3(3.1f, 2.2f, 4.3f);
    s.radius = radius;
    ScalarGrid g;
    const int n = static_cast<int>(std::ceil(2.0f * (radius + 2.0f * spacing) / spacing)) + 1;
    g.reset(n, n, n, s.center - Vec3(radius + 2.0f * spacing), spacing);
    for (int k = 0; k < n; ++k)
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) g.values[g.index(i, j, k)] = radius - glm::length(g.position(i, j, k) - s.center);
    extract_surface(g, 0.0f, s.mesh);
    return s;
}

/// A 17 x 13 procedural valley (rows != columns, so u and v cannot be swapped unseen).
inline Terrain small_terrain() {
    auto t = Terrain::build(procedural_valley(17, 13, 5), TerrainDef{.area_scale = 1.0f, .height_scale = 6.0f});
    EXPECT_TRUE(t.ok());
    return std::move(t.value());
}

/// `n` particles of which the first `active` are active; ids a permutation, velocities
/// and birth frames (<= solver_frame) all different.
inline Particles sample_particles(size_t n, size_t active, uint32_t solver_frame) {
    Particles p;
    p.resize(n);
    Lcg rng(7);
    for (size_t i = 0; i < n; ++i) {
        p.position[i] = Vec3(rng.uniform(0.0f, 8.0f), rng.uniform(0.0f, 3.0f), rng.uniform(0.0f, 6.0f));
        p.velocity[i] = Vec3(rng.uniform(-2.0f, 2.0f), rng.uniform(-2.0f, 2.0f), rng.uniform(-2.0f, 2.0f));
        p.id[i] = static_cast<uint32_t>((i * 7 + 3) % n);
        p.birth_frame[i] = static_cast<uint32_t>(i % (solver_frame + 1));
        p.active[i] = i < active ? 1 : 0;
    }
    return p;
}

/// A program on PATH, or empty.
inline std::string find_program(const std::string& name) {
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "");
    std::string dir;
    while (std::getline(dirs, dir, ':')) {
        const std::filesystem::path candidate = std::filesystem::path(dir) / name;
        if (!dir.empty() && ::access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate))
            return candidate.string();
    }
    return {};
}

class ExportFixture : public CliFixture {
protected:
    /// Writes `bytes` to dir_/name and returns the path.
    std::filesystem::path put(const std::string& name, const std::string& bytes) {
        const auto p = dir_ / name;
        std::ofstream(p, std::ios::binary) << bytes;
        return p;
    }
};

}  // namespace mr::test
