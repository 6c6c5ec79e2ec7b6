// A block of particles dropped all at once into the procedural bowl (33 x 33 samples,
// 7 m deep) with the default river's physics, no continuous source and no sink: the
// still pool of the sound-water tests and the render tests' foam splash.
#pragma once

#include <metariver/scene.h>

namespace mr::test {

inline SceneDef bowl_drop(int count, Vec3 center, Vec3 half_extent) {
    SceneDef d = default_scene();
    d.source = {.kind = TerrainSource::Bowl, .heightmap = {}, .width = 33, .height = 33, .seed = 7};
    d.terrain.height_scale = 7.0f;
    d.spawn.count = count;
    d.spawn.auto_center = false;
    d.spawn.auto_channel = false;
    d.spawn.center = center;
    d.spawn.half_extent = half_extent;
    d.spawn.interval = 0;
    d.spawn.flow_rate = 0.0f;
    d.spawn.shape = SourceShape::Box;
    d.sink.kind = SinkKind::None;
    return d;
}

}  // namespace mr::test
