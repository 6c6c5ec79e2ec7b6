// A still PBF pool for the bodies' tests (issue 44): a flat floor at y = 0, 4 x 4 m between
// walls 10 m high (one sample of slope each side: 10:1), filled on the rest lattice.
#pragma once

#include <metariver/scene.h>

#include <algorithm>
#include <cmath>

namespace mr::test {

struct Pool {
    SceneDef def;
    Heightmap map;
    float depth = 0.0f;  ///< the water's lattice depth, metres
    /// Horizontal area of the water at height y (the walls slope 10:1 over one metre).
    static float area(float y) {
        const float side = 4.0f + 2.0f * std::clamp(y, 0.0f, 10.0f) / 10.0f;
        return side * side;
    }
};

/// `spacing`: the PBF rest spacing; `layers`: the water's depth in spacings.
inline Pool still_pool(float spacing, int layers) {
    Pool p;
    p.map = flat_heightmap(9, 9);
    for (int r = 0; r < 9; ++r)
        for (int c = 0; c < 9; ++c)
            if (r < 2 || c < 2 || r >= 7 || c >= 7) p.map.samples[size_t(r) * 9 + size_t(c)] = 1.0f;
    SceneDef d = default_scene();
    d.name = "bodies pool";
    d.surface = false;
    d.foam.enabled = false;
    d.pbf.auto_spacing = false;
    scale_river_lengths(d, spacing);
    d.source = {.kind = TerrainSource::Flat, .heightmap = {}, .width = 9, .height = 9, .seed = 1};
    d.terrain.height_scale = 10.0f;
    d.terrain.area_scale = 1.0f;
    d.terrain.auto_area_scale = false;
    d.terrain.condition = TerrainCondition::None;
    // The lattice source over the floor: (2k + 1) points per axis around the centre.
    const int k = int(std::floor(1.9f / spacing));
    const float he = float(k) * spacing;
    d.spawn.auto_center = false;
    d.spawn.auto_channel = false;
    d.spawn.shape = SourceShape::Box;
    d.spawn.center = Vec3(4.0f, 0.5f * spacing + 0.5f * float(layers - 1) * spacing, 4.0f);
    d.spawn.half_extent = Vec3(he + 0.01f * spacing, 0.5f * float(layers - 1) * spacing + 0.01f * spacing, he + 0.01f * spacing);
    d.spawn.count = (2 * k + 1) * (2 * k + 1) * layers;
    d.spawn.interval = 0;
    d.spawn.flow_rate = 0.0f;
    d.spawn.prefill = false;
    d.sink.kind = SinkKind::None;
    p.depth = float(layers) * spacing;
    p.def = d;
    return p;
}

}  // namespace mr::test
