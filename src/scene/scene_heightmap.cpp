// Heightmaps for scenes: procedural terrains or a PNG file.
#include <metariver/scene.h>

#include <fmt/format.h>

namespace mr {

Result<Heightmap> load_scene_heightmap(const SceneDef& def) {
    const auto& s = def.source;
    switch (s.kind) {
        case TerrainSource::Valley: return procedural_valley(s.width, s.height, s.seed);
        case TerrainSource::Strict: return procedural_strict(s.width, s.height);
        case TerrainSource::Bowl: return procedural_bowl(s.width, s.height);
        case TerrainSource::Flat: return flat_heightmap(s.width, s.height);
        case TerrainSource::Waterfall: return procedural_waterfall(s.width, s.height);
        case TerrainSource::Weir: return procedural_weir(s.width, s.height);
        case TerrainSource::Alps: {
            // assets/heightmaps/real/alps.png, read into the library at configure time (src/CMakeLists.txt)
            static constexpr uint8_t kAlpsPng[] = {
#include "alps_png.inc"
            };
            return load_heightmap_png_memory(kAlpsPng, "alps (assets/heightmaps/real/alps.png)");
        }
        case TerrainSource::File:
            if (s.heightmap.empty())
                return Error{fmt::format("scene '{}' needs a heightmap file (give --heightmap FILE)", def.name)};
            return load_heightmap_png(s.heightmap);
    }
    return Error{"unknown terrain source"};
}

}  // namespace mr
