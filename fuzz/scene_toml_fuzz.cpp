// libFuzzer target: the TOML scene parser with its validation (mr::parse_scene_toml,
// the code `--scene FILE` runs), and for small procedural scenes what Simulation::create
// checks next: the terrain built from the scene and validate_on_terrain.
//
// Properties: a scene the parser accepts passes validate() again (parse returns only
// valid scenes) and every error message is one line naming the origin.
#include <metariver/scene.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>
#include <string_view>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const mr::SceneDef base = mr::default_scene();
    const std::string_view text(reinterpret_cast<const char*>(data), size);
    auto def = mr::parse_scene_toml(text, "fuzz.toml", base);
    if (!def) {
        const std::string& m = def.error().message;
        if (m.rfind("fuzz.toml", 0) != 0) std::abort();  // names the file first
        if (m.find('\n') != std::string::npos) std::abort();  // one line
        return 0;
    }
    const mr::SceneDef& d = def.value();
    if (!mr::validate(d)) std::abort();
    (void)mr::scene_warnings(d);
    // The terrain of a small procedural scene (files are not read here).
    if (d.source.kind != mr::TerrainSource::File && d.source.width <= 129 && d.source.height <= 129) {
        auto map = mr::load_scene_heightmap(d);
        if (!map) return 0;
        auto terrain = mr::Terrain::build(map.value(), d.terrain);
        if (!terrain) return 0;
        (void)mr::validate_on_terrain(d, terrain.value());
    }
    return 0;
}
