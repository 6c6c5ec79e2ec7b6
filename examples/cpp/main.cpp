// The default river from the installed package: create the scene, step it two seconds (120
// frames at 60 per second) and print what the simulation holds then.
#include <metariver/scene.h>

#include <cstdio>

int main() {
    // The default scene: PBF water on the procedural valley (docs/scene-format.md).
    const mr::SceneDef scene = mr::default_scene();
    auto sim = mr::Simulation::create(scene);
    if (!sim) {
        std::fprintf(stderr, "river: %s\n", sim.error().message.c_str());
        return 1;
    }
    for (int frame = 0; frame < 120; ++frame) (*sim)->step(1.0f / 60.0f);

    const mr::Simulation& s = **sim;
    std::printf("frames: %llu\n", static_cast<unsigned long long>(s.frame()));
    std::printf("active particles: %zu\n", s.particles().active_count());
    std::printf("surface triangles: %zu\n", s.surface().triangle_count());
    return 0;
}
