// The default river from the installed package: create the scene, step it two seconds (120
// frames at 60 per second), print what the simulation holds then and ask the water at one
// point (docs/getting-started.md, "Install the library").
#include <metariver/scene.h>
#include <metariver/water_query.h>

#include <glm/geometric.hpp>

#include <cstdio>
#include <vector>

int main() {
    // The default scene: PBF water on the procedural valley (docs/scene-format.md).
    auto created = mr::Simulation::create(mr::default_scene());
    if (!created) {
        std::fprintf(stderr, "river: %s\n", created.error().message.c_str());
        return 1;
    }
    mr::Simulation& sim = **created;
    for (int frame = 0; frame < 120; ++frame) sim.step(1.0f / 60.0f);

    const mr::SurfaceMesh& surface = sim.surface();
    std::printf("frames: %llu\n", static_cast<unsigned long long>(sim.frame()));
    std::printf("active particles: %zu\n", sim.particles().active_count());
    std::printf("surface triangles: %zu\n", surface.triangle_count());
    if (surface.triangle_count() == 0 || sim.particles().active_count() == 0) return 0;

    // The water where the middle one of the active particles is.
    std::vector<mr::Vec3> positions;
    sim.particles().gather_active_positions(positions);
    const mr::Vec3 c = positions[positions.size() / 2];
    mr::WaterQuery water;
    water.update(sim);
    const mr::WaterSample w = water.sample(c.x, c.z);
    std::printf("water at (%.2f, %.2f): %s, surface y %.3f m, depth %.3f m, speed %.3f m/s\n", c.x, c.z,
                w.wet ? "wet" : "dry", w.surface_y, w.depth, glm::length(w.velocity));
    return 0;
}
