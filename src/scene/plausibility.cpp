// Plausibility measures of a particle state that need the terrain: spray (particles
// thrown out of the water) and the speeds of the active particles.
#include <metariver/neighbor_grid.h>
#include <metariver/scene.h>

#include <algorithm>

namespace mr {

float spray_fraction(const Terrain& terrain, std::span<const Vec3> positions, std::span<const uint8_t> active,
                     float kernel_radius, float spacing) {
    const size_t n = std::min(positions.size(), active.size());
    size_t count = 0;
    for (size_t i = 0; i < n; ++i) count += active[i] != 0;
    if (count == 0 || !(kernel_radius > 0.0f)) return 0.0f;

    NeighborGrid grid;
    grid.build(positions.first(n), active.first(n), kernel_radius);
    const float r2 = kernel_radius * kernel_radius;
    const float clearance = 2.0f * spacing;
    size_t spray = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!active[i]) continue;
        const Vec3 p = positions[i];
        // Near the ground (or on it) a particle is water however alone it is.
        if (terrain.contains_xz(p.x, p.z) && !(p.y - terrain.height_mesh(p.x, p.z) > clearance)) continue;
        int neighbours = 0;
        grid.for_each_candidate(p, [&](uint32_t j) {
            const Vec3 d = positions[j] - p;
            neighbours += j != i && d.x * d.x + d.y * d.y + d.z * d.z < r2;
        });
        spray += neighbours < kSprayNeighbours;
    }
    return static_cast<float>(double(spray) / double(count));
}

}  // namespace mr
