// Scene defaults, the built-in presets and validation of every field.
//
// The paper's scenes come from its repository's Unity scene files (see docs/scenes.md):
// FullVersion (own physics) on strict17.png, Nile on nile.png.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr {

// [bullet]'s setting, here with the scene's other settings: a build without Bullet
// (METARIVER_WITH_BULLET=OFF) still reads and writes scenes that hold it.
std::string_view to_string(BulletTerrainShape s) {
    switch (s) {
        case BulletTerrainShape::Mesh: return "mesh";
        case BulletTerrainShape::Heightfield: return "heightfield";
    }
    return "?";
}

std::string_view to_string(TerrainSource s) {
    switch (s) {
        case TerrainSource::Valley: return "valley";
        case TerrainSource::Strict: return "strict";
        case TerrainSource::Bowl: return "bowl";
        case TerrainSource::Flat: return "flat";
        case TerrainSource::File: return "file";
        case TerrainSource::Waterfall: return "waterfall";
        case TerrainSource::Weir: return "weir";
        case TerrainSource::Alps: return "alps";
    }
    return "?";
}

std::string collision_mode_unused(SolverKind solver, CollisionMode mode) {
    if (solver == SolverKind::Bullet)
        return "solver = \"bullet\" does not use it ([bullet] has its contact settings)";
    if (solver == SolverKind::Pbf && mode == CollisionMode::Paper)
        return "solver = \"pbf\" slides along the terrain (\"robust\") or ignores it (\"none\"); \"paper\" "
               "(reflection) is solver = \"springs\"'s response";
    return {};
}

std::string seed_unused(SolverKind solver) {
    if (solver == SolverKind::Pbf)
        return "solver = \"pbf\" does not use it (its lattice source places every particle it emits: nothing is "
               "random); remove it";
    if (solver == SolverKind::Hybrid) return "solver = \"hybrid\" does not use it (nothing it does is random); remove it";
    return {};
}

SceneDef default_scene() {
    return SceneDef{};  // the member defaults are the default river (scene.h)
}

namespace {
/// The base of the springs presets: every table at its own type's defaults (the paper's
/// springs solver), which each preset then fills; not the default river's values.
SceneDef springs_base() {
    SceneDef d;
    d.solver = SolverKind::Springs;
    d.source = TerrainSourceDef{};
    d.terrain = TerrainDef{};
    d.spawn = SpawnDef{};
    d.springs = SpringDef{};
    d.collision = CollisionDef{};
    d.integrator = IntegratorDef{};
    d.pbf = PbfDef{};
    d.sink = SinkDef{};
    d.field = FieldDef{};
    d.smoothing = SmoothingDef{};
    d.foam = FoamDef{};
    return d;
}
}  // namespace

SceneDef springs_valley_scene() {
    // A stream down the procedural valley with the paper's own physics: low damping so
    // particles slide along the channel instead of sticking, soft springs so they keep
    // apart, and a field threshold that wraps small groups of balls.
    SceneDef d = springs_base();
    d.name = "default";  // the default scene before issue 5: preset "springs-valley"
    d.seed = 1;
    d.source = {.kind = TerrainSource::Valley, .heightmap = {}, .width = 65, .height = 97, .seed = 7};
    d.terrain = {.area_scale = 1.0f, .height_scale = 24.0f, .paper_row_orientation = true};
    d.spawn = {.count = 300,
               .center = Vec3(0.0f),
               .half_extent = Vec3(1.5f, 0.5f, 1.5f),
               .interval = 2,
               .initial_velocity = Vec3(0.0f, 0.0f, -2.0f),
               .auto_center = true,
               .auto_height = 1.5f};
    d.springs = {.stiffness = 4.0f, .min_distance = 1.0f, .max_distance = 0.5f, .mode = SpringMode::Pairs};
    d.collision = {.mode = CollisionMode::Robust, .damping = 0.003f, .offset = 0.02f, .leaf_triangles = 8};
    d.integrator = {.gravity = 9.82f, .fixed_dt = 0.0f, .substeps = 1};
    d.field = {.kernel = FieldKernel::InverseSquare,
               .radius = 1.0f,
               .resolution = 1.5f,
               .bounds_offset = 2.0f,
               .threshold = 0.08f};
    return d;
}

namespace {

/// The paper's FullVersion scene (own physics): strict17.png, 20 balls, springs off.
SceneDef paper_full() {
    SceneDef d = springs_base();
    d.name = "paper-full";
    d.seed = 1;
    d.source = {.kind = TerrainSource::File, .heightmap = {}, .width = 17, .height = 17, .seed = 1};
    d.terrain = {.area_scale = 1.0f, .height_scale = 7.0f, .paper_row_orientation = true};
    d.spawn = {.count = 20,
               .center = Vec3(8.0f, 7.0f, 15.0f),
               .half_extent = Vec3(2.0f, 1.0f, 0.2f),
               .interval = 80,
               .initial_velocity = Vec3(0.0f)};
    d.springs = {.stiffness = 0.0f, .min_distance = 3.0f, .max_distance = 5.0f, .mode = SpringMode::Pairs};
    d.collision = {.mode = CollisionMode::Paper, .damping = 0.7f, .offset = 0.07f, .leaf_triangles = 8};
    d.integrator = {.gravity = 9.82f, .fixed_dt = 0.0f, .substeps = 1};
    d.field = {.kernel = FieldKernel::InverseSquare,
               .radius = 2.0f,
               .resolution = 2.0f,
               .bounds_offset = 4.0f,
               .threshold = 0.54f};
    return d;
}

/// The paper's Nile scene (engine physics in the paper) run with the paper's own
/// physics: nile.png, 50 balls every 15 frames, resolution 1, threshold 0.32, offset 5.
SceneDef paper_nile() {
    SceneDef d = paper_full();
    d.name = "paper-nile";
    d.source = {.kind = TerrainSource::File, .heightmap = {}, .width = 33, .height = 33, .seed = 1};
    d.spawn.count = 50;
    d.spawn.center = Vec3(27.0f, 4.6f, 31.0f);
    d.spawn.half_extent = Vec3(2.5f, 1.0f, 1.0f);
    d.spawn.interval = 15;
    d.field.resolution = 1.0f;
    d.field.threshold = 0.32f;
    d.field.bounds_offset = 5.0f;
    return d;
}

/// Figure 6: the bowl with springs on, keeping the balls apart. The paper gives no
/// scene file for it; FullVersion's parameters with k = 2 and the spawn volume over
/// the bowl's centre.
SceneDef paper_bowl() {
    SceneDef d = paper_full();
    d.name = "paper-bowl";
    d.source = {.kind = TerrainSource::Bowl, .heightmap = {}, .width = 33, .height = 33, .seed = 1};
    d.spawn.center = Vec3(16.0f, 8.0f, 16.0f);
    d.spawn.half_extent = Vec3(2.0f, 1.0f, 2.0f);
    d.spawn.interval = 20;
    d.springs.stiffness = 2.0f;
    return d;
}

/// The paper's engine-physics scenes (2.4) on Bullet: rigid spheres against the
/// terrain mesh, no springs, no sphere-sphere collisions, the engine's gravity (Unity's
/// default, 9.81: the paper's scenes were Unity scenes). NativeCollision: strict17.png,
/// 40 balls every 8 frames, field resolution 1, threshold 0.48, bounds offset 4.
SceneDef paper_engine() {
    SceneDef d = paper_full();
    d.name = "paper-engine";
    d.solver = SolverKind::Bullet;
    d.spawn.count = 40;
    d.spawn.interval = 8;
    d.integrator.gravity = 9.81f;
    d.field.resolution = 1.0f;
    d.field.threshold = 0.48f;
    d.field.bounds_offset = 4.0f;
    return d;
}

/// The paper's Nile scene with its engine physics: paper-nile's parameters on Bullet.
SceneDef paper_nile_engine() {
    SceneDef d = paper_nile();
    d.name = "paper-nile-engine";
    d.solver = SolverKind::Bullet;
    d.integrator.gravity = 9.81f;
    return d;
}


/// The hybrid solver's scenes (docs/waterfalls.md): the grid with PBF particles of 0.2 m
/// where it falls, on a procedural channel 1 m per sample; the particles move as a river's
/// (no sleeping or slow-water damping), the field sized to their spacing.
SceneDef hybrid_base(std::string name, TerrainSource kind, float discharge) {
    SceneDef d;
    d.name = std::move(name);
    d.solver = SolverKind::Hybrid;
    d.source = {.kind = kind, .heightmap = {}, .width = 40, .height = 80, .seed = 1};
    d.terrain = {.area_scale = 1.0f, .height_scale = 20.0f, .paper_row_orientation = false,
                 .condition = TerrainCondition::None};
    d.spawn.count = 20;  // the particles' budget is hybrid.max_particles
    d.spawn.flow_rate = 0.0f;
    d.spawn.prefill = false;
    d.spawn.auto_center = false;
    d.spawn.auto_channel = false;
    d.spawn.center = Vec3(19.5f, 15.0f, 77.0f);
    d.sink.kind = SinkKind::None;
    d.foam.enabled = false;
    d.hybrid.max_particles = 2000;  // about 4x what the falls hold
    d.swe.discharge = discharge;
    d.swe.auto_source = false;
    d.swe.source_center = Vec3(19.5f, 0.0f, 77.0f);
    d.pbf = PbfDef{.spacing = 0.2f, .kernel_radius = 0.4f};
    d.pbf.auto_spacing = false;
    d.field.radius = 0.7f;  // 3.5 spacings: the falling sheet's particles spread apart and still join
    d.field.threshold = 0.3f;
    d.field.resolution = 7.5f;
    d.field.bounds_offset = 0.7f;
    return d;
}

/// A river over a 10 m cliff into a plunge pool (procedural_waterfall), 3 m^3/s poured 13 m
/// above the lip, the reach above the lip full to 1 m over it at the start (so that it falls
/// from the first frame).
SceneDef hybrid_waterfall() {
    SceneDef d = hybrid_base("waterfall", TerrainSource::Waterfall, 3.0f);
    d.swe.initial_level = 0.62f * 20.0f + 1.0f;
    d.swe.source_center = Vec3(19.5f, 0.0f, 68.0f);
    d.swe.dam_z = 0.7f * 79.0f;  // the lip's row: the pool below starts dry
    return d;
}

/// A channel across a weir 2 m above the bed upstream, 4 m above it downstream, 3 m^3/s; the
/// pond behind it full to 0.3 m over the crest at the start.
SceneDef hybrid_weir() {
    SceneDef d = hybrid_base("weir", TerrainSource::Weir, 3.0f);
    d.hybrid.drop = 0.5f;
    d.swe.initial_level = 0.6f * 20.0f + 0.3f;
    d.swe.dam_z = 0.47f * 79.0f;  // the weir's downstream face: dry below it
    return d;
}

/// The hybrid on a real DEM with steep reaches: the ETOPO5 Alps crop (terrain.source =
/// "alps", built in) shrunk to 15 m per sample and 400 m of relief, so that its valley heads
/// drop more than hybrid.drop (3 m) between neighbouring cells; its pits filled (the DEM's
/// pits would hold the river in a pool at its head); 50 m^3/s poured at the head of the main
/// channel, the river spun up before frame 0 (swe.init = "steady"). Particles of 0.5 m: a
/// fall off a 15 m cell is metres wide.
SceneDef hybrid_alps() {
    SceneDef d = hybrid_base("waterfall-alps", TerrainSource::Alps, 50.0f);
    d.source = {.kind = TerrainSource::Alps, .heightmap = {}, .width = 108, .height = 61, .seed = 1};
    d.terrain.area_scale = 15.0f;
    d.terrain.height_scale = 400.0f;
    d.terrain.condition = TerrainCondition::Fill;
    d.spawn.auto_center = true;  // swe.source_center "auto": the head of the main channel
    d.spawn.auto_channel = true;
    d.swe.auto_source = true;
    d.swe.init = SweInit::Steady;
    d.hybrid.drop = 3.0f;
    d.hybrid.min_grade = 0.2f;  // its reaches that drop 3 m over a 15 m cell (22 % grades) shed
    d.pbf = PbfDef{.spacing = 0.5f, .kernel_radius = 1.0f};
    d.pbf.auto_spacing = false;
    d.field.radius = 1.75f;  // 3.5 spacings, as the waterfall's
    d.field.resolution = 3.0f;
    d.field.bounds_offset = 1.75f;
    return d;
}

}  // namespace

std::vector<std::string> preset_names() {
    return {"default", "springs-valley", "paper-full", "paper-nile", "paper-bowl", "paper-engine", "paper-nile-engine",
            "waterfall", "weir", "waterfall-alps"};
}

Result<SceneDef> preset(std::string_view name) {
    if (name == "default") return default_scene();
    if (name == "springs-valley") {
        SceneDef d = springs_valley_scene();
        d.name = "springs-valley";
        return d;
    }
    if (name == "paper-full") return paper_full();
    if (name == "paper-nile") return paper_nile();
    if (name == "paper-bowl") return paper_bowl();
    if (name == "paper-engine") return paper_engine();
    if (name == "paper-nile-engine") return paper_nile_engine();
    if (name == "waterfall") return hybrid_waterfall();
    if (name == "weir") return hybrid_weir();
    if (name == "waterfall-alps") return hybrid_alps();
    std::string known;
    for (const auto& n : preset_names()) known += (known.empty() ? "" : ", ") + n;
    return Error{fmt::format("unknown preset '{}' (known: {})", name, known)};
}

Status validate(const SceneDef& d) {
    // Every key's own range where the scene reads it (scene_keys(): a key no solver of
    // this scene reads keeps whatever value; the viewer shows it once it is read).
    for (const SceneKey& k : scene_keys())
        if (k.readers(d))
            if (std::string e = key_range_error(k, d); !e.empty()) return Error{fmt::format("{}: {}", k.name, e)};
    // Ranges that depend on another key, and sizes the reference paths cannot finish.
    std::string error;
    auto check = [&](bool ok, std::string_view message, const auto&... args) {
        if (error.empty() && !ok) error = fmt::vformat(message, fmt::make_format_args(args...));
    };
    const float carve = d.carve_spacing;  // programmatic only (SceneDef::carve_spacing)
    check(std::isfinite(carve) && carve >= 0.0f && carve <= 1e3f, "carve_spacing: must be in [0, 1000] (got {})", carve);
    // Accepted input must finish a frame in bounded time: the O(N^2) and O(balls x
    // samples) reference paths are refused above a size, naming the fast alternative.
    check(!(d.solver == SolverKind::Springs && d.springs.stiffness > 0.0f && d.springs.mode == SpringMode::Pairs &&
            d.spawn.count > kMaxPairsParticles),
          "springs.mode: \"pairs\" (the paper's O(N^2) serial loop) is limited to {} particles (got particles.count = "
          "{}): use springs.mode = \"grid\" (same forces)",
          kMaxPairsParticles, d.spawn.count);
    check(!(d.surface && d.field.kernel != FieldKernel::Poly6 && d.spawn.count > kMaxDenseFieldBalls),
          "field.kernel: the paper's kernels reach every grid sample (O(balls x samples)) and are limited to {} balls "
          "(got particles.count = {}): use field.kernel = \"poly6\" or surface = false",
          kMaxDenseFieldBalls, d.spawn.count);
    check(!(d.solver == SolverKind::Bullet && d.spawn.count > kMaxBulletBodies),
          "particles.count: solver = \"bullet\" is limited to {} rigid bodies (got {}); use solver = \"pbf\" or "
          "\"springs\" for more",
          kMaxBulletBodies, d.spawn.count);
    check(!(d.field.bounds == FieldBounds::Terrain && d.field.kernel != FieldKernel::Poly6),
          "field.bounds: \"terrain\" needs a compact kernel (field.kernel = \"poly6\"); the paper's kernels reach every sample");
    if (d.solver == SolverKind::Pbf || d.solver == SolverKind::Hybrid)
        check(d.pbf.kernel_radius > d.pbf.spacing && d.pbf.kernel_radius <= 4.0f * d.pbf.spacing,
              "pbf.kernel_radius: must be in (pbf.spacing, 4 pbf.spacing] = ({}, {}] (got {})", d.pbf.spacing,
              4.0f * d.pbf.spacing, d.pbf.kernel_radius);
    if ((d.solver == SolverKind::Pbf || d.solver == SolverKind::Hybrid) && d.foam.enabled) {  // FoamSystem's ranges
        const FoamDef& f = d.foam;
        auto above = [&](const char* hi_key, float hi, const char* lo_key, float lo) {
            check(hi > lo, "{}: must be in ({} = {}, {}] (got {})", hi_key, lo_key, lo, find_scene_key(hi_key)->range.hi, hi);
        };
        above("foam.trapped_air_max", f.trapped_air_max, "foam.trapped_air_min", f.trapped_air_min);
        above("foam.wave_crest_max", f.wave_crest_max, "foam.wave_crest_min", f.wave_crest_min);
        above("foam.energy_max", f.energy_max, "foam.energy_min", f.energy_min);
        check(f.lifetime_max >= f.lifetime_min, "foam.lifetime_max: must be in [foam.lifetime_min = {}, 1000] (got {})",
              f.lifetime_min, f.lifetime_max);
        check(f.bubble_neighbours >= f.spray_neighbours,
              "foam.bubble_neighbours: must be in [foam.spray_neighbours = {}, 1000] (got {})", f.spray_neighbours,
              f.bubble_neighbours);
    }
    if (d.solver != SolverKind::Bullet && d.sink.kind == SinkKind::Box)
        check(d.sink.min.x <= d.sink.max.x && d.sink.min.y <= d.sink.max.y && d.sink.min.z <= d.sink.max.z,
              "sink.max: every component must be >= sink.min's");
    if (const std::string e = list_range_error(d); !e.empty()) check(false, "{}", e);
    if (const std::string e = bodies_error(d); !e.empty()) check(false, "{}", e);
    if (d.solver != SolverKind::Bullet)
        for (size_t i = 0; i < d.sink.boxes.size(); ++i) {
            const SinkBox& b = d.sink.boxes[i];
            check(b.min.x <= b.max.x && b.min.y <= b.max.y && b.min.z <= b.max.z,
                  "sink.box[{}].max: every component must be >= sink.box[{}].min's", i + 1, i + 1);
        }
    if (!error.empty()) return Error{error};
    return Ok{};
}

Status validate_on_terrain(const SceneDef& d, const Terrain& t) {
    const Aabb b = t.bounds();
    // The sources: the main one, then the more sources where the scene reads them.
    const bool more = d.solver != SolverKind::Bullet && (d.spawn.auto_rate() ? d.solver == SolverKind::Pbf : d.spawn.has_rate());
    const size_t sources = 1 + (more ? d.spawn.sources.size() : 0);
    for (size_t k = 0; k < sources; ++k) {
        const Vec3 c = k == 0 ? d.spawn.center : d.spawn.sources[k - 1].center;
        const Vec3 half = k == 0 ? d.spawn.half_extent : d.spawn.sources[k - 1].half_extent;
        const std::string centre = source_key(k, SourceField::Center), extent = source_key(k, SourceField::HalfExtent);
        const Vec3 he = source_half_size(d.spawn.shape, half);  // as the emitters read it
        if (!t.contains_xz(c.x, c.z))
            return Error{fmt::format("{}: the source at [{}, {}, {}] is outside the terrain's rectangle "
                                     "x in [0, {}], z in [0, {}]",
                                     centre, c.x, c.y, c.z, b.max.x, b.max.z)};
        const Vec3 lo = c - he, hi = c + he;
        auto overlaps = [&](const SinkBox& s) {
            return lo.x <= s.max.x && hi.x >= s.min.x && lo.y <= s.max.y && hi.y >= s.min.y && lo.z <= s.max.z &&
                   hi.z >= s.min.z;
        };
        if (d.sink.kind == SinkKind::Box && overlaps(SinkBox{d.sink.min, d.sink.max}))
            return Error{fmt::format("sink.min/sink.max: the sink box overlaps the source volume around [{}, {}, {}] "
                                     "({}): particles would be recycled as they are born",
                                     c.x, c.y, c.z, centre)};
        if (d.solver != SolverKind::Bullet)
            for (size_t i = 0; i < d.sink.boxes.size(); ++i)
                if (overlaps(d.sink.boxes[i]))
                    return Error{fmt::format("sink.box[{}]: the sink box overlaps the source volume around [{}, {}, {}] "
                                             "({}): particles would be recycled as they are born",
                                             i + 1, c.x, c.y, c.z, centre)};
        if (d.sink.kind == SinkKind::Edges && (!t.contains_xz(lo.x, lo.z) || !t.contains_xz(hi.x, hi.z)))
            return Error{fmt::format("{}: the source volume around [{}, {}, {}] crosses the terrain's edge, which is "
                                     "the sink (sink.kind = \"edges\")",
                                     extent, c.x, c.y, c.z)};
    }
    return Ok{};
}

std::vector<std::string> scene_warnings(const SceneDef& d) {
    std::vector<std::string> w;
    const float rate = d.spawn.total_particles_per_second();  // every source
    if (rate > float(d.spawn.count))
        w.push_back(fmt::format("particles.flow_rate: {} particles per second is more than the whole particle "
                                "budget (particles.count = {}) every second: the source runs dry and the flow is "
                                "capped by the budget; lower the rate or raise particles.count",
                                rate, d.spawn.count));
    else if (rate > 0.0f && rate * 5.0f > float(d.spawn.count))
        w.push_back(fmt::format("particles.flow_rate: {} particles per second empties the budget of {} "
                                "(particles.count) in {:.1f} s; a river longer than that runs with gaps",
                                rate, d.spawn.count, float(d.spawn.count) / rate));
    if (rate > 0.0f && d.sink.kind == SinkKind::None)
        w.push_back("sink.kind: none with a particles.flow_rate: particles are only recycled when they leave the "
                    "terrain's box; set sink.kind = \"edges\" for a river");
    return w;
}

}  // namespace mr
