// The C API's creation (include/metariver/metariver.h): the world's scene from a file, a
// TOML text, a preset or the default; its terrain from the scene, a PNG or the caller's
// heights; the scales' and the threads' overrides. Every refusal names the field of
// mr_world_desc (or the scene's key, or the file) and what it takes.
#include "capi_internal.h"

#include <metariver/terrain.h>

#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <type_traits>
#include <vector>

#ifndef METARIVER_VERSION
#define METARIVER_VERSION "0.0.0"
#endif
#ifndef METARIVER_GIT_COMMIT
#define METARIVER_GIT_COMMIT "unknown"
#endif

namespace mr::capi {

bool finite3(const float* p) { return std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]); }

const mr::HeightfieldWater* heightfield_of(const mr_world* world, const char* function, mr_status& status) {
    const mr::HeightfieldWater* w = world->sim->heightfield();
    status = w ? MR_OK
               : fail(world, MR_ERROR_UNSUPPORTED,
                      fmt::format("{}: solver = \"{}\" has no water grid (its water is particles; solver = \"swe\" has one)",
                                  function, world->sim->solver_entry().kind.name));
    return w;
}

std::string show3(const float* p) { return fmt::format("{}, {}, {}", p[0], p[1], p[2]); }

namespace {

/// Largest scales the desc takes, metres (the CLI's --area-scale and --height-scale).
constexpr double kMaxAreaScale = 1e4;
constexpr double kMaxHeightScale = 1e5;
/// Most threads a world's arena takes, the Simulation's own bound: TBB sizes an arena's
/// slots by it (a million threads asked held 540 MB before any work).
constexpr int kMaxThreads = mr::Simulation::kMaxThreads;

/// A refusal during creation: the code and the message for mr_error.
struct Refusal {
    mr_status code = MR_OK;
    std::string message;
};

template <class T>
struct Made {  // a value or a refusal
    T value{};
    Refusal refusal;
    bool ok() const { return refusal.code == MR_OK; }
};

Refusal refuse(mr_status code, std::string message) { return {code, std::move(message)}; }

/// A file the caller named can be opened for reading ("scene_file: cannot read 'x.toml'").
Refusal check_readable(const char* field, const char* path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return refuse(MR_ERROR_IO, fmt::format("{}: cannot read '{}' (no such file, or not readable)", field, path));
    return {};
}

/// A scale override: 0 (the scene's) or finite in (0, hi] metres.
Refusal check_scale(const char* field, float v, double hi) {
    if (v == 0.0f) return {};
    if (!(std::isfinite(v) && v > 0.0f && v <= hi))
        return refuse(MR_ERROR_INVALID_ARGUMENT,
                      fmt::format("{}: must be 0 (the scene's) or in (0, {}] metres (got {})", field, hi, v));
    return {};
}

/// The desc's own fields, before any file is read.
Refusal check_desc(const mr_world_desc& d) {
    std::vector<std::string> sources;
    if (d.scene_file) sources.emplace_back("scene_file");
    if (d.scene_toml) sources.emplace_back("scene_toml");
    if (d.preset) sources.emplace_back("preset");
    if (sources.size() > 1)
        return refuse(MR_ERROR_INVALID_ARGUMENT,
                      fmt::format("{}: set at most one of scene_file, scene_toml and preset", fmt::join(sources, ", ")));
    if (d.heights && d.heightmap_file)
        return refuse(MR_ERROR_INVALID_ARGUMENT, "heightmap_file, heights: set at most one terrain");
    if (d.threads < 0 || d.threads > kMaxThreads)
        return refuse(MR_ERROR_INVALID_ARGUMENT,
                      fmt::format("threads: must be in [0, {}] (0: every core) (got {})", kMaxThreads, d.threads));
    if (Refusal r = check_scale("area_scale", d.area_scale, kMaxAreaScale); r.code) return r;
    if (Refusal r = check_scale("height_scale", d.height_scale, kMaxHeightScale); r.code) return r;
    return {};
}

/// The caller's heights as a Heightmap. Its samples are in IMAGE order (terrain.h): with
/// the paper's row orientation (image row r at z = (rows-1-r) s) the caller's row k (at
/// z = k s) is image row rows-1-k; without it, image row k.
Made<Heightmap> heights_map(const mr_world_desc& d, bool paper_rows) {
    Made<Heightmap> m;
    if (d.columns < 2 || d.columns > kMaxHeightmapSide || d.rows < 2 || d.rows > kMaxHeightmapSide) {
        const char* which = d.columns < 2 || d.columns > kMaxHeightmapSide ? "columns" : "rows";
        m.refusal = refuse(MR_ERROR_INVALID_ARGUMENT,
                           fmt::format("{}: must be in [2, {}] with heights (got columns {}, rows {})", which,
                                       kMaxHeightmapSide, d.columns, d.rows));
        return m;
    }
    const size_t w = static_cast<size_t>(d.columns), h = static_cast<size_t>(d.rows);
    m.value.width = d.columns;
    m.value.height = d.rows;
    m.value.bit_depth = 32;
    m.value.samples.resize(w * h);
    for (size_t k = 0; k < h; ++k) {
        const size_t image_row = paper_rows ? h - 1 - k : k;
        for (size_t c = 0; c < w; ++c) {
            const float v = d.heights[k * w + c];
            if (!(std::isfinite(v) && v >= 0.0f && v <= 1.0f)) {
                m.refusal = refuse(MR_ERROR_INVALID_ARGUMENT,
                                   fmt::format("heights[{}] (row {}, column {}): must be finite and in [0, 1] (got {})",
                                               k * w + c, k, c, v));
                return m;
            }
            m.value.samples[image_row * w + c] = v;
        }
    }
    return m;
}

/// The scene the desc names (file, TOML text, preset or the default), before overrides.
Made<SceneDef> desc_scene(const mr_world_desc& d) {
    Made<SceneDef> m;
    if (d.scene_file) {
        if (Refusal r = check_readable("scene_file", d.scene_file); r.code) return {{}, r};
        auto s = load_scene_file(d.scene_file, d.heightmap_file ? d.heightmap_file : "");
        if (!s) return {{}, refuse(MR_ERROR_SCENE, "scene_file: " + s.error().message)};
        m.value = std::move(s.value());
    } else if (d.scene_toml) {
        auto s = parse_scene_toml(d.scene_toml, "scene_toml", default_scene());
        if (!s) return {{}, refuse(MR_ERROR_SCENE, s.error().message)};
        m.value = std::move(s.value());
    } else if (d.preset) {
        auto s = preset(d.preset);
        if (!s) return {{}, refuse(MR_ERROR_INVALID_ARGUMENT, "preset: " + s.error().message)};
        m.value = std::move(s.value());
    } else {
        m.value = default_scene();
    }
    if (d.heightmap_file) {
        m.value.source.kind = TerrainSource::File;
        m.value.source.heightmap = d.heightmap_file;
    }
    if (d.area_scale != 0.0f) {
        m.value.terrain.area_scale = d.area_scale;
        m.value.terrain.auto_area_scale = false;
    }
    if (d.height_scale != 0.0f) m.value.terrain.height_scale = d.height_scale;
    if (auto v = validate(m.value); !v) return {{}, refuse(MR_ERROR_SCENE, v.error().message)};
    return m;
}

/// The terrain's heightmap: the caller's heights, a PNG (heightmap_file or the scene's
/// file) or the scene's procedural terrain.
Made<Heightmap> desc_terrain(const mr_world_desc& d, const SceneDef& def) {
    if (d.heights) return heights_map(d, def.terrain.paper_row_orientation);
    if (def.source.kind == TerrainSource::File) {
        const char* field = d.heightmap_file ? "heightmap_file" : "terrain.heightmap";
        if (def.source.heightmap.empty())
            return {{}, refuse(MR_ERROR_SCENE, fmt::format("scene '{}' uses a heightmap file: set heightmap_file (or "
                                                           "terrain.heightmap in the scene)", def.name))};
        if (Refusal r = check_readable(field, def.source.heightmap.c_str()); r.code) return {{}, r};
        auto map = load_heightmap_png(def.source.heightmap);
        if (!map) return {{}, refuse(MR_ERROR_IO, fmt::format("{}: {}", field, map.error().message))};
        return {std::move(map.value()), {}};
    }
    auto map = load_scene_heightmap(def);
    if (!map) return {{}, refuse(MR_ERROR_SCENE, map.error().message)};
    return {std::move(map.value()), {}};
}

/// Builds the world the desc describes, inside its own arena.
Made<std::unique_ptr<mr_world>> create_world(const mr_world_desc& d) {
    if (Refusal r = check_desc(d); r.code) return {{}, r};
    Made<SceneDef> def = desc_scene(d);
    if (!def.ok()) return {{}, def.refusal};
    Made<Heightmap> map = desc_terrain(d, def.value);
    if (!map.ok()) return {{}, map.refusal};
    auto world = std::make_unique<mr_world>(d.threads);
    if (d.preset) world->base = d.preset;
    auto sim = world->arena.execute([&] { return Simulation::create(def.value, map.value); });
    if (!sim) return {{}, refuse(MR_ERROR_SCENE, sim.error().message)};
    world->sim = std::move(sim.value());
    // The Simulation runs its work in an arena of its own (set_threads), which a call
    // entering it from the world's arena does not inherit: without this its steps and
    // edits would run on every core whatever desc.threads says.
    if (auto t = world->sim->set_threads(d.threads); !t) return {{}, refuse(MR_ERROR_INVALID_ARGUMENT, t.error().message)};
    return {std::move(world), {}};
}

void fill_error(mr_error* error, mr_status code, const std::string& message) {
    if (!error) return;
    error->code = code;
    const size_t n = std::min(message.size(), sizeof(error->message) - 1);
    std::memcpy(error->message, message.data(), n);
    error->message[n] = '\0';
}

}  // namespace
}  // namespace mr::capi

extern "C" {

mr_world_desc mr_world_desc_default(void) {
    mr_world_desc d;
    std::memset(&d, 0, sizeof d);
    return d;
}

uint32_t mr_api_version(void) { return MR_API_VERSION; }

const char* mr_version_string(void) { return "metariver " METARIVER_VERSION " (commit " METARIVER_GIT_COMMIT ")"; }

const char* mr_status_name(mr_status status) {
    std::underlying_type_t<mr_status> code = 0;  // a C caller may pass any int (see mr_world_sculpt)
    std::memcpy(&code, &status, sizeof code);
    switch (code) {
        case MR_OK: return "MR_OK";
        case MR_ERROR_NULL_ARGUMENT: return "MR_ERROR_NULL_ARGUMENT";
        case MR_ERROR_INVALID_ARGUMENT: return "MR_ERROR_INVALID_ARGUMENT";
        case MR_ERROR_SCENE: return "MR_ERROR_SCENE";
        case MR_ERROR_IO: return "MR_ERROR_IO";
        case MR_ERROR_UNSUPPORTED: return "MR_ERROR_UNSUPPORTED";
        case MR_ERROR_BUFFER_TOO_SMALL: return "MR_ERROR_BUFFER_TOO_SMALL";
        case MR_ERROR_INTERNAL: return "MR_ERROR_INTERNAL";
    }
    return "MR_STATUS_UNKNOWN";
}

mr_status mr_world_create(const mr_world_desc* desc, mr_world** out_world, mr_error* error) {
    using namespace mr::capi;
    fill_error(error, MR_OK, "");
    if (out_world) *out_world = nullptr;
    if (!desc || !out_world) {
        fill_error(error, MR_ERROR_NULL_ARGUMENT, fmt::format("mr_world_create: {} is NULL", desc ? "out_world" : "desc"));
        return MR_ERROR_NULL_ARGUMENT;
    }
    try {
        auto made = create_world(*desc);
        if (!made.ok()) {
            fill_error(error, made.refusal.code, made.refusal.message);
            return made.refusal.code;
        }
        *out_world = made.value.release();
        return MR_OK;
    } catch (const std::bad_alloc&) {
        fill_error(error, MR_ERROR_INTERNAL, "mr_world_create: out of memory");
    } catch (const std::exception& e) {
        fill_error(error, MR_ERROR_INTERNAL, fmt::format("mr_world_create: internal error: {}", e.what()));
    } catch (...) {
        fill_error(error, MR_ERROR_INTERNAL, "mr_world_create: internal error (unknown exception)");
    }
    return MR_ERROR_INTERNAL;
}

void mr_world_destroy(mr_world* world) {
    try {
        delete world;
    } catch (...) {  // a destructor that throws: nothing a C caller could do
    }
}

const char* mr_world_last_error(const mr_world* world) { return world ? world->error.c_str() : "world is NULL"; }

}  // extern "C"
