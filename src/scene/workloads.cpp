#include <metariver/workloads.h>

#include <algorithm>
#include <cmath>
#include <random>

namespace mr {

float w2_height(float x, float z) {
    const float pi = 3.14159265358979323846f;
    const float u = (x - 128.0f) / 128.0f;
    const float xc = 128.0f + 16.0f * std::sin(2.0f * pi * z / 128.0f);
    const float a = std::max(0.0f, 1.0f - z / 24.0f);
    const float b = std::max(0.0f, 1.0f - (256.0f - z) / 24.0f);
    const float q = (x - xc) / 8.0f;
    return 40.0f * u * u + 10.0f * z / 256.0f - 4.0f * std::exp(-q * q) + 30.0f * a * a + 30.0f * b * b;
}

Heightmap w2_heightmap() {
    Heightmap m = flat_heightmap(257, 257);
    // Image row r is z = r (paper_row_orientation = false), column c is x = c.
    for (int r = 0; r < 257; ++r)
        for (int c = 0; c < 257; ++c) m.samples[static_cast<size_t>(r) * 257 + c] = w2_height(float(c), float(r));
    return m;
}

TerrainDef w2_terrain_def() { return TerrainDef{.area_scale = 1.0f, .height_scale = 1.0f, .paper_row_orientation = false}; }

std::vector<Vec3> w2_spheres(int n, uint32_t seed) {
    Lcg rng(seed);
    std::vector<Vec3> s(static_cast<size_t>(std::max(n, 0)));
    constexpr float y0 = 12.0f;
    for (int k = 0; k < n; ++k) {
        const int l = k / 5640, iz = (k % 5640) / 40, ix = k % 40;
        const float jx = static_cast<float>((rng.next() - 0.5) * 0.2);
        const float jy = static_cast<float>((rng.next() - 0.5) * 0.2);
        const float jz = static_cast<float>((rng.next() - 0.5) * 0.2);
        s[static_cast<size_t>(k)] = Vec3(104.0f + 1.25f * float(ix) + jx, y0 + 1.25f * float(l) + jy,
                                         40.0f + 1.25f * float(iz) + jz);
    }
    return s;
}

SceneDef river_scene(int n) {
    SceneDef d = springs_valley_scene();
    d.name = "river-" + std::to_string(n);
    d.spawn.count = n;
    d.spawn.interval = 0;
    // Keep the water volume: spacing ~ (V / n)^(1/3) with V ~ 300 m^3 at the default.
    const float spacing = std::clamp(std::cbrt(300.0f / static_cast<float>(n)), 0.12f, 1.0f);
    d.spawn.half_extent = Vec3(4.0f, 1.5f, 6.0f) * std::max(1.0f, spacing * 1.5f);
    d.spawn.auto_height = 2.0f;
    // Stiff enough that a pile several layers deep keeps its spacing under gravity
    // (k * overlap ~ depth * g); two substeps keep the explicit integration stable.
    d.springs.mode = SpringMode::Grid;
    d.springs.stiffness = 600.0f;
    d.springs.min_distance = spacing;
    d.springs.max_distance = 0.25f * spacing;
    d.integrator.substeps = 2;
    d.collision.damping = 0.05f;
    d.collision.query = CollisionQuery::Heightfield;
    d.collision.radius = 0.0f;
    // Compact kernel reaching 1.5 spacings, samples 1.5 per spacing: a ball touches
    // ~50 samples, so the field costs O(n), and the surface wraps groups of particles.
    d.field.kernel = FieldKernel::Poly6;
    d.field.radius = 1.5f * spacing;
    d.field.resolution = std::min(64.0f, 1.5f / spacing);
    d.field.bounds_offset = d.field.radius;
    d.field.threshold = 0.4f;
    return d;
}

SceneDef pbf_river_scene(int n) {
    SceneDef d = default_scene();
    const float s0 = d.pbf.spacing;  // 0.5 m: the spacing the default river sizes itself for
    const float s = std::clamp(s0 * std::cbrt(kPbfRiverSteadyParticles / float(std::max(n, 1))), 0.05f, 1.0f);
    const float k = s / s0;
    d.name = "pbf-river-" + std::to_string(n);
    d.carve_spacing = s0;  // the default's channel and basin, whatever the spacing
    d.pbf.auto_spacing = false;
    // Samples per metre follow the spacing up to kPbfRiverMaxFieldResolution: the field's
    // box spans the river's bounding box (up to 65 x 97 x 25 m), whose dense sample
    // count must stay under kMaxFieldSamples.
    scale_river_lengths(d, s, kPbfRiverMaxFieldResolution);
    // The default's self-sized rate (27 particles/s of 0.125 m^3 on the valley: carve
    // 3 m x 1 m, kRiverFill at kRiverSpeed) as a volume: the same river, finer.
    SceneDef sized = default_scene();
    const float rate0 = size_river(sized, sized.terrain.area_scale, 0.0f).rate;
    d.spawn.flow_rate = rate0 / (k * k * k);
    d.spawn.count = std::max(1, int(std::ceil(1.5f * float(n))));
    return d;
}

std::vector<Vec3> w3_block(int nx, Vec3 origin) {
    constexpr float d = kW3Spacing;
    std::vector<Vec3> block;
    block.reserve(size_t(std::max(nx, 0)) * size_t(std::max(nx, 0)) * size_t(std::max(nx / 2, 0)));
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> jitter(-0.01f * d, 0.01f * d);
    for (int a = 0; a < nx; ++a)
        for (int b = 0; b < nx; ++b)
            for (int c = 0; c < nx / 2; ++c) {
                const float x = float(a) * d + jitter(rng), y = float(c) * d + jitter(rng), z = float(b) * d + jitter(rng);
                block.push_back(origin + Vec3(x, y, z));
            }
    return block;
}

}  // namespace mr
