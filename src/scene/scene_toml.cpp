// Scene files in TOML (toml++). Every key is checked: unknown keys, wrong types and
// out-of-range values are one-line errors naming the file and the key. The keys, their
// types and ranges come from the table in scene_keys.cpp (docs/scene-format.md is
// generated from it); the rules between keys (what a solver or another key's value
// makes irrelevant) are here.
#include <metariver/scene.h>
#include <metariver/scene_keys.h>

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <vector>

namespace mr {

namespace {

/// Reads keys of the table (scene_keys()) from a parsed file; the first error wins.
class Reader {
public:
    explicit Reader(std::string origin) : origin_(std::move(origin)) {}

    bool failed() const { return !error_.empty(); }
    const std::string& error() const { return error_; }

    void fail(const std::string& key, const std::string& what) {
        if (error_.empty()) error_ = fmt::format("{}: {}: {}", origin_, key, what);
    }

    /// Rejects keys of `t` not in `allowed`.
    void allow(const toml::table& t, const std::string& prefix, const std::vector<std::string_view>& allowed) {
        for (const auto& [k, v] : t) {
            if (std::find(allowed.begin(), allowed.end(), k.str()) != allowed.end()) continue;
            std::string list;
            for (auto a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
            fail(prefix + std::string(k.str()), fmt::format("unknown key (allowed here: {})", list));
            return;
        }
    }

    const toml::table* table(const toml::table& root, std::string_view key) {
        const toml::node* n = root.get(key);
        if (!n) return nullptr;
        if (!n->is_table()) {
            fail(std::string(key), "must be a table ([" + std::string(key) + "])");
            return nullptr;
        }
        return n->as_table();
    }

    /// Reads `k` from `t` (its section's table) into `d` when the file has it: the type
    /// is checked, an integer's range too (it must fit); the other numbers' ranges are
    /// checked by check_range once the scene is complete. Returns whether it was given.
    bool key(const toml::table& t, const SceneKey& k, SceneDef& d) {
        const toml::node* n = t.get(k.leaf());
        if (!n) return false;
        return value(*n, k, std::string(k.name), d, [&] { return k.field(d); });
    }

    /// Reads the list `l` from its section's table `t` when the file has it (an array
    /// of tables, at most l.max, each with only the list's keys); the entries replace
    /// the base scene's (validate() checks their ranges).
    void list(const toml::table& t, const SceneList& l, SceneDef& d) {
        const toml::node* n = t.get(l.leaf());
        if (!n) return;
        const std::string name(l.name);
        const toml::array* a = n->as_array();
        if (!a || !a->is_array_of_tables())
            return fail(name, fmt::format("must be a list of tables, each written [[{}]]", name));
        if (a->size() > l.max) return fail(name, fmt::format("at most {} entries (got {})", l.max, a->size()));
        l.resize(d, 0);
        l.resize(d, a->size());
        std::vector<std::string_view> allowed;
        for (const SceneListKey& k : l.keys) allowed.push_back(k.key.name);
        for (size_t i = 0; i < a->size() && !failed(); ++i) {
            const toml::table& e = *(*a)[i].as_table();
            allow(e, fmt::format("{}[{}].", name, i + 1), allowed);
            for (const SceneListKey& k : l.keys)
                if (const toml::node* v = e.get(k.key.name))
                    value(*v, k.key, l.entry_key(i, k), d, [&] { return k.item(d, i); });
        }
    }

    /// Reads `node` into the field `field()` finds, as key `k` (its type, words and an
    /// integer's range), naming it `key` in messages.
    template <class Field>
    bool value(const toml::node& node, const SceneKey& k, const std::string& key, SceneDef& d, Field&& field) {
        const toml::node* n = &node;
        if (k.words.apply && n->is_string()) {
            const std::string s = *n->value<std::string>();
            for (size_t i = 0; i < k.words.words.size(); ++i)
                if (s == k.words.words[i]) {
                    k.words.apply(d, static_cast<int>(i));
                    return true;
                }
            fail(key, fmt::format("must be {} or {}", quoted(k.words.words, " or "), what(k)));
            return true;
        }
        const FieldRef f = field();
        switch (k.type) {
            case KeyType::Bool:
                if (!n->is_boolean()) return fail(key, "must be true or false"), true;
                *std::get<bool*>(f) = n->as_boolean()->get();
                break;
            case KeyType::Int:
            case KeyType::Seed: {
                if (!n->is_integer()) return fail(key, fmt::format("must be an integer {}", k.range.phrase())), true;
                const long long v = n->as_integer()->get();
                if (!k.range.contains(static_cast<double>(v)))
                    return fail(key, fmt::format("must be {} (got {})", k.range.phrase(), v)), true;
                if (k.type == KeyType::Int) *std::get<int*>(f) = static_cast<int>(v);
                else *std::get<uint32_t*>(f) = static_cast<uint32_t>(v);
                break;
            }
            case KeyType::Float: {
                const auto v = n->value<double>();  // accepts integers too
                if (!v) return fail(key, "must be a number"), true;
                const auto x = static_cast<float>(*v);
                if (!std::isfinite(x) && std::isfinite(*v)) return fail(key, fmt::format("out of float range (got {})", *v)), true;
                *std::get<float*>(f) = x;
                break;
            }
            case KeyType::Vec3: {
                const toml::array* a = n->as_array();
                Vec3 out;
                for (int c = 0; a && a->size() == 3 && c < 3; ++c) {
                    auto v = (*a)[static_cast<size_t>(c)].value<double>();
                    if (!v) a = nullptr;
                    else out[c] = static_cast<float>(*v);
                }
                if (!a || a->size() != 3) return fail(key, "must be an array of 3 numbers [x, y, z]"), true;
                *std::get<Vec3*>(f) = out;
                break;
            }
            case KeyType::String: {
                auto s = n->value<std::string>();
                if (!s) return fail(key, "must be a string"), true;
                *std::get<std::string*>(f) = *s;
                break;
            }
            case KeyType::Choice: {
                auto s = n->value<std::string>();
                if (!s) return fail(key, "must be a string"), true;
                const auto it = std::find(k.choices.begin(), k.choices.end(), *s);
                if (it == k.choices.end())
                    return fail(key, fmt::format("must be one of {} (got '{}')", quoted(k.choices, ", ", ""), *s)), true;
                const EnumRef& e = std::get<EnumRef>(f);
                e.set(e.field, static_cast<int>(it - k.choices.begin()));
                break;
            }
        }
        if (k.words.apply) k.words.apply(d, -1);  // a number, not a word
        return true;
    }

    /// The range of a number the file gave (the table's static range).
    void check_range(const SceneKey& k, const SceneDef& d) {
        if (const std::string e = key_range_error(k, d); !e.empty()) fail(std::string(k.name), e);
    }

private:
    static std::string quoted(std::span<const std::string_view> words, const char* sep, const char* quote = "\"") {
        std::string s;
        for (auto w : words) s += fmt::format("{}{}{}{}", s.empty() ? "" : sep, quote, w, quote);
        return s;
    }
    /// What a number-typed key takes besides its words.
    static std::string what(const SceneKey& k) {
        if (k.type == KeyType::Vec3) return "an array of 3 numbers [x, y, z]";
        return fmt::format("a {} {}", k.type == KeyType::Float ? "number" : "whole number", k.range.phrase());
    }

    std::string origin_;
    std::string error_;
};

/// Options the chosen solver does not read: a key that asks for something the solver
/// does not do is an error naming the key. What each reads (src/particles/solver.cpp,
/// pbf.cpp, bullet_solver.cpp, src/scene/simulation.cpp):
///   [pbf]       solver = "pbf"; the others read pbf.spacing only to carve a channel
///               (terrain.condition = "carve": its depth and width, carve_def)
///   [bullet]    solver = "bullet"
///   [springs]   solver = "springs"; Bullet the stiffness and distances with
///               bullet.springs = true (not springs.mode); PBF none of it
///   [collision] springs and PBF (PBF never reflects: no mode = "paper"); not Bullet
///   integrator.substeps: springs and PBF (Bullet substeps by bullet.dt)
///   seed        springs and Bullet (PBF's lattice source draws no random number)
///   [foam]      solver = "pbf" (enabled = false is accepted anywhere)
/// What a Bullet scene would otherwise inherit from the default river (its flow-rate
/// source, edge sinks and spawn-all-at-once) is replaced by the paper's engine
/// scene's spawning.
void apply_solver_scope(const toml::table& root, Reader& r, SceneDef& d) {
    const std::string solver = fmt::format("solver = \"{}\"", to_string(d.solver));
    const toml::table* pt = root["particles"].as_table();
    const toml::table* st = root["springs"].as_table();
    auto given = [&](const char* key) { return pt && pt->get(key) != nullptr; };
    auto in = [](const toml::table* t, const char* key) { return t && t->get(key) != nullptr; };

    if (const toml::table* pbf = root["pbf"].as_table(); pbf && d.solver != SolverKind::Pbf) {
        if (d.terrain.condition != TerrainCondition::Carve) {
            r.fail("pbf", fmt::format("only solver = \"pbf\" reads [pbf] ({} reads pbf.spacing only to carve a "
                                      "channel, terrain.condition = \"carve\")", solver));
        } else {
            for (const auto& [k, v] : *pbf)
                if (k.str() != "spacing")
                    r.fail("pbf." + std::string(k.str()),
                           fmt::format("only solver = \"pbf\" reads it ({} reads pbf.spacing only, the carved "
                                       "channel's depth)", solver));
        }
    }
    if (const toml::table* ft = root["foam"].as_table(); ft && d.solver != SolverKind::Pbf)
        for (const auto& [k, v] : *ft)
            if (k.str() != "enabled" || d.foam.enabled)
                r.fail("foam." + std::string(k.str()),
                       fmt::format("only solver = \"pbf\" makes foam (diffuse particles need the fluid's kernel "
                                   "neighbourhoods; {} has none): remove [foam]", solver));
    if (root.get("bullet") && d.solver != SolverKind::Bullet)
        r.fail("bullet", fmt::format("only solver = \"bullet\" reads [bullet] (this scene has {})", solver));
    if (st && d.solver == SolverKind::Pbf)
        r.fail("springs", "solver = \"pbf\" does not use springs (its density constraint keeps the particles "
                          "apart: [pbf]); remove [springs]");
    // PBF draws no random number: its lattice source places every particle it emits.
    if (const std::string why = seed_unused(d.solver); root.get("seed") && !why.empty()) r.fail("seed", why);
    if (const toml::table* ct = root["collision"].as_table(); ct && ct->get("mode") && d.solver == SolverKind::Pbf) {
        if (const std::string why = collision_mode_unused(d.solver, d.collision.mode); !why.empty())
            r.fail("collision.mode", why);
    }
    if (d.solver != SolverKind::Bullet) return;

    const std::string why = "solver = \"bullet\" does not use it (spheres spawn in the box every "
                            "particles.spawn_interval frames, collide through Bullet and respawn below or outside the terrain)";
    if (given("flow_rate") && (d.spawn.flow_rate > 0.0f || d.spawn.auto_rate())) r.fail("particles.flow_rate", why + "; remove it or set 0");
    if (given("litres_per_particle") && d.spawn.litres_per_particle > 0.0f) r.fail("particles.litres_per_particle", why);
    if (given("source_shape") && d.spawn.shape != SourceShape::Box) r.fail("particles.source_shape", why + "; only \"box\"");
    if (root.get("collision")) r.fail("collision", collision_mode_unused(d.solver, d.collision.mode));
    if (const toml::table* sk = root["sink"].as_table(); sk && d.sink.kind != SinkKind::None)
        r.fail("sink.kind", why + "; only \"none\"");
    if (in(st, "mode"))
        r.fail("springs.mode", "solver = \"bullet\" applies the springs itself (bullet.springs); remove springs.mode");
    if (!d.bullet.springs) {
        const char* off = "solver = \"bullet\" applies springs only with bullet.springs = true";
        if (in(st, "stiffness") && d.springs.stiffness != 0.0f) r.fail("springs.stiffness", fmt::format("{}; set 0 or turn them on", off));
        for (const char* k : {"min_distance", "max_distance"})
            if (in(st, k)) r.fail(fmt::format("springs.{}", k), off);
    }
    if (in(root["integrator"].as_table(), "substeps"))
        r.fail("integrator.substeps", "solver = \"bullet\" substeps with its own fixed step (bullet.dt, "
                                      "bullet.max_substeps); remove it");
    // Not inherited from the default river:
    if (!given("flow_rate")) d.spawn.flow_rate = 0.0f;
    if (!given("litres_per_particle")) d.spawn.litres_per_particle = 0.0f;
    if (!given("source_shape")) d.spawn.shape = SourceShape::Box;
    if (!root.get("sink")) d.sink = SinkDef{};
    if (!given("spawn_interval")) {
        auto engine = preset("paper-engine");
        if (engine) d.spawn.interval = engine->spawn.interval;
    }
}

/// Keys another key's value makes irrelevant (issue 13, "no silent option"): a key
/// written in the file that the scene as written never reads is an error naming the
/// key and the key/value that makes it irrelevant, with the way out. Only keys present
/// in the file are checked (what is inherited from the base scene is never an error);
/// the deciding value may be inherited (a spawn_interval under the default river's
/// flow_rate = "auto"). A value that agrees with what the scene does anyway (bullet.sleep
/// = false with bullet.springs = true, litres_per_particle = 0 without a rate) is
/// accepted, as springs.stiffness = 0 is in a Bullet scene without springs. Checked
/// against the code that reads each key (after apply_solver_scope, which settles what
/// each solver reads at all):
///   surface.enabled = false   the smoothing keys of [surface]; surface.method = "none"
///                       or iterations = 0: the other smoothing keys; method = "taubin":
///                       steps, keep_volume; steps = "uniform": pass_band; "chebyshev":
///                       lambda; a field.kernel other than poly6: feature_count > 0
///   surface = false     [field] except resolution (Simulation::step builds no field;
///                       field.resolution stays: the default --voxel-size of --export
///                       --format vdb, export_options.cpp)
///   field.kernel = "inverse_square"   field.radius (1/r^2 has none: paper_field.cpp)
///   a particle rate     spawn_interval (ParticleSolver::step_frame: the interval only
///                       schedules activations without a rate); a rate is flow_rate > 0,
///                       or "auto" with solver = "pbf" (sized from the channel)
///   no particle rate    litres_per_particle > 0 (the unit of flow_rate); flow_rate =
///                       "auto" outside PBF (Simulation::create sets it to 0)
///   spawn_center [x, y, z]   auto_height (resolve_source: "auto"/"channel" only)
///   source_shape = "point"   spawn_half_extent (spawn, LatticeSource: one point)
///   sink.kind other than "box"   sink.min, sink.max
///   springs.stiffness = 0    min_distance, max_distance, mode (no spring force)
///   collision.mode = "none"  damping, offset, query (no terrain contact; radius stays:
///                            the tunneled counter reads it)
///   collision.mode = "paper" query (the paper's response walks the AABB tree)
///   terrain.source = "file"  width, height, seed (the PNG's size; no procedure)
///   terrain.source = strict | bowl | flat   seed (only "valley" is random); heightmap
///   terrain.source = valley              heightmap
///   pbf.scorr_k = 0          scorr_n, scorr_dq (no tensile correction: pbf.cpp)
///   foam.enabled = false     every other [foam] key (Simulation makes no FoamSystem)
///   bullet.max_substeps = 0  bullet.dt (one Bullet step of the frame's time)
///   bullet.springs = true    bullet.sleep = true (spheres with springs never sleep)
/// The viewer's live editor can change any value after loading; a key is judged by the
/// scene as written, as the solver scope is.
void refuse_irrelevant_keys(const toml::table& root, Reader& r, const SceneDef& d) {
    auto given = [&](const char* table, const char* key) {
        const toml::table* t = root[table].as_table();
        return t && t->get(key) != nullptr;
    };
    auto ignored = [&](const std::string& key, const std::string& when, const std::string& fix) {
        r.fail(key, fmt::format("ignored when {}: {}", when, fix));
    };
    auto each = [&](const char* table, std::initializer_list<const char*> keys, const std::string& when,
                    const std::string& fix) {
        for (const char* k : keys)
            if (given(table, k)) ignored(fmt::format("{}.{}", table, k), when, fix);
    };

    const bool surface_table = root["surface"].is_table();
    const std::string off = surface_table ? "surface.enabled = false" : "surface = false";
    if (!d.surface)
        each("field", {"kernel", "bounds", "radius", "bounds_offset", "threshold"},
             off + " (no field or surface is built; field.resolution stays, the default voxel size of --export "
                   "--format vdb)",
             fmt::format("remove it or set {} = true", surface_table ? "surface.enabled" : "surface"));
    else if (d.field.kernel == FieldKernel::InverseSquare)
        each("field", {"radius"}, "field.kernel = \"inverse_square\" (1/r^2 has no radius)",
             "remove it or use field.kernel = \"radius_over_r\" or \"poly6\"");

    // The smoothing ([surface]): smooth_surface (src/surface/smoothing.cpp) returns at
    // once for method "none" or 0 iterations; Taubin steps lambda|mu and never restores
    // the volume; Laplacian's uniform steps are lambda, its Chebyshev steps come from
    // pass_band; feature weights read a poly6 field (Simulation::step passes none else).
    if (surface_table) {
        const SmoothingDef& m = d.smoothing;
        if (!d.surface)
            each("surface", {"method", "steps", "iterations", "lambda", "pass_band", "feature_count", "keep_volume",
                             "normal_iterations", "smooth_hidden"},
                 "surface.enabled = false (nothing is smoothed)", "remove it or set enabled = true");
        else if (m.method == SmoothingMethod::None)
            each("surface", {"steps", "iterations", "lambda", "pass_band", "feature_count", "keep_volume", "normal_iterations", "smooth_hidden"},
                 "surface.method = \"none\" (the mesh as extracted)", "remove it or choose a method");
        else if (m.iterations == 0)
            each("surface", {"steps", "lambda", "pass_band", "feature_count", "keep_volume", "normal_iterations", "smooth_hidden"},
                 "surface.iterations = 0 (no smoothing step)", "remove it or give iterations");
        else {
            if (m.method == SmoothingMethod::Taubin)
                each("surface", {"steps", "keep_volume"},
                     "surface.method = \"taubin\" (lambda|mu steps, which keep the volume themselves)",
                     "remove it or use method = \"laplacian\"");
            else if (m.steps == SmoothingSteps::Uniform)
                each("surface", {"pass_band"}, "surface.steps = \"uniform\" (every step is lambda)",
                     "remove it or use steps = \"chebyshev\"");
            else
                each("surface", {"lambda"}, "surface.steps = \"chebyshev\" (the step sizes come from pass_band)",
                     "remove it or use steps = \"uniform\"");
            if (d.field.kernel != FieldKernel::Poly6 && m.feature_count != 0.0f)
                each("surface", {"feature_count"},
                     fmt::format("field.kernel = \"{}\" (feature weights read a poly6 field)", to_string(d.field.kernel)),
                     "remove it or use field.kernel = \"poly6\"");
        }
    }

    // The source: a rate (flow_rate > 0, or "auto" sized for a PBF river) or one
    // activation every spawn_interval frames. Bullet's flow_rate is 0 here already.
    const bool auto_rate = d.spawn.auto_rate() && d.solver == SolverKind::Pbf;
    const bool by_rate = auto_rate || (!d.spawn.auto_rate() && d.spawn.has_rate());
    const bool flow_given = given("particles", "flow_rate");
    if (by_rate) {
        const std::string rate =
            auto_rate ? fmt::format("particles.flow_rate = \"auto\"{} (the source emits at the river's sized rate)",
                                    flow_given ? "" : " (the default river's)")
                      : fmt::format("particles.flow_rate > 0 (the source emits {} {} per second)", d.spawn.flow_rate,
                                    d.spawn.litres_per_particle > 0.0f ? "litres" : "particles");
        each("particles", {"spawn_interval"}, rate, "remove it or set flow_rate = 0");
    }
    if (d.spawn.auto_rate() && flow_given && d.solver != SolverKind::Pbf)
        r.fail("particles.flow_rate",
               fmt::format("\"auto\" sizes a PBF river (solver = \"pbf\"); solver = \"{}\" would run it as 0 (one "
                           "activation every spawn_interval frames): give a rate in particles per second, or 0",
                           to_string(d.solver)));
    if (!by_rate && given("particles", "litres_per_particle") && d.spawn.litres_per_particle > 0.0f)
        ignored("particles.litres_per_particle",
                flow_given ? "particles.flow_rate = 0 (it is flow_rate's unit)"
                           : fmt::format("particles.flow_rate is 0 (solver = \"{}\" without a flow_rate; it is "
                                         "flow_rate's unit)", to_string(d.solver)),
                "remove it or give a flow_rate");
    if (!d.spawn.auto_center)
        each("particles", {"auto_height"}, "particles.spawn_center is [x, y, z] (it places an \"auto\" or \"channel\" centre)",
             "remove it or set spawn_center = \"auto\"");
    if (d.spawn.shape == SourceShape::Point)
        each("particles", {"spawn_half_extent"}, "particles.source_shape = \"point\" (every particle starts at the centre)",
             "remove it or use source_shape = \"box\" or \"disc\"");
    if (d.sink.kind != SinkKind::Box)
        each("sink", {"min", "max"}, fmt::format("sink.kind = \"{}\" (only a box sink has corners)",
                                                 d.sink.kind == SinkKind::None ? "none" : "edges"),
             "remove it or set kind = \"box\"");

    // The channel's prefill needs PBF water and a carved channel to fill.
    if (d.solver != SolverKind::Pbf)
        each("particles", {"prefill"}, fmt::format("solver = \"{}\" (only PBF water fills the carved channel)", to_string(d.solver)),
             "remove it or use solver = \"pbf\"");
    else if (resolved_condition(d) != TerrainCondition::Carve)
        each("particles", {"prefill"},
             fmt::format("terrain.condition resolves to \"{}\" (no carved channel to fill)", to_string(resolved_condition(d))),
             "remove it or set terrain.condition = \"carve\"");

    // Springs, where the solver reads [springs] at all (solver scope refused the rest).
    if (d.springs.stiffness == 0.0f && (d.solver == SolverKind::Springs || (d.solver == SolverKind::Bullet && d.bullet.springs)))
        each("springs", {"min_distance", "max_distance", "mode"}, "springs.stiffness = 0 (no spring force)",
             "remove it or give a stiffness");

    if (d.solver != SolverKind::Bullet) {
        if (d.collision.mode == CollisionMode::None)
            each("collision", {"damping", "offset", "query", "friction_speed"},
                 "collision.mode = \"none\" (particles pass through the terrain)", "remove it or set mode = \"robust\"");
        else if (d.collision.mode == CollisionMode::Paper)
            each("collision", {"query"}, "collision.mode = \"paper\" (the paper's response walks the AABB tree; query "
                                         "picks robust mode's)",
                 "remove it or set mode = \"robust\"");
        if (d.solver == SolverKind::Springs)
            each("collision", {"friction_speed"}, "solver = \"springs\" (a bounce's damping has no law; only PBF's bed friction)",
                 "remove it or use solver = \"pbf\"");
    }

    const std::string source = fmt::format("terrain.source = \"{}\"", to_string(d.source.kind));
    if (d.source.kind == TerrainSource::File)
        each("terrain", {"width", "height", "seed"}, source + " (the PNG gives the size; nothing is generated)",
             "remove it or use a procedural source");
    else {
        each("terrain", {"heightmap"}, source + " (a procedural terrain)", "remove it or set source = \"file\"");
        if (d.source.kind != TerrainSource::Valley)
            each("terrain", {"seed"}, source + " (only \"valley\" is random)", "remove it or use source = \"valley\"");
    }

    if (d.solver == SolverKind::Pbf && !d.foam.enabled)
        each("foam", {"max_particles", "trapped_air_min", "trapped_air_max", "wave_crest_min", "wave_crest_max",
                      "energy_min", "energy_max", "trapped_air_rate", "wave_crest_rate", "lifetime_min", "lifetime_max",
                      "spray_neighbours", "bubble_neighbours", "buoyancy", "drag"},
             "foam.enabled = false (no diffuse particles are made)", "remove it or set foam.enabled = true");
    if (d.solver == SolverKind::Pbf && d.pbf.scorr_k == 0.0f)
        each("pbf", {"scorr_n", "scorr_dq"}, "pbf.scorr_k = 0 (no tensile-instability correction)",
             "remove it or give a scorr_k");
    if (d.solver == SolverKind::Bullet) {
        if (d.bullet.max_substeps == 0)
            each("bullet", {"dt"}, "bullet.max_substeps = 0 (one Bullet step of the frame's time)",
                 "remove it or allow substeps (max_substeps >= 1)");
        if (d.bullet.springs && d.bullet.sleep && given("bullet", "sleep"))
            ignored("bullet.sleep", "bullet.springs = true (spheres with springs never sleep)",
                    "remove it or set sleep = false");
    }
}

/// Messages stay one line whatever the file holds: control characters that reach a
/// message (a quoted key or a string value with a newline in it, toml++'s quote of the
/// text at a syntax error) are written as escapes. Found by fuzz/scene_toml_fuzz.cpp:
/// `sleep = fals` then a newline gave "expected 'false', saw 'fals" and a line break.
std::string one_line(std::string_view s) {
    std::string out;
    out.reserve(s.size());
    for (const char ch : s) {
        const auto c = static_cast<unsigned char>(ch);
        if (c == '\n') out += "\\n";
        else if (c == '\r') out += "\\r";
        else if (c == '\t') out += "\\t";
        else if (c < 0x20 || c == 0x7f) out += fmt::format("\\x{:02x}", c);
        else out += ch;
    }
    return out;
}

Result<SceneDef> parse_scene_toml_lines(std::string_view text, const std::string& origin, const SceneDef& base);

}  // namespace

Result<SceneDef> parse_scene_toml(std::string_view text, const std::string& origin, const SceneDef& base) {
    auto d = parse_scene_toml_lines(text, origin, base);
    if (!d) return Error{one_line(d.error().message)};
    return d;
}

namespace {

Result<SceneDef> parse_scene_toml_lines(std::string_view text, const std::string& origin, const SceneDef& base) {
    toml::table root;
    try {
        root = toml::parse(text, origin);
    } catch (const toml::parse_error& e) {
        return Error{fmt::format("{}:{}:{}: TOML syntax error: {}", origin, e.source().begin.line,
                                 e.source().begin.column, e.description())};
    }

    // `preset = "NAME"`: the file starts from that preset instead of `base` (what
    // `metariver scene --preset NAME` writes, so that the keys its scene does not read,
    // which the file cannot hold, keep the preset's values).
    SceneDef d = base;
    if (const toml::node* n = root.get("preset")) {
        const auto name = n->value<std::string>();
        auto p = name ? preset(*name) : Result<SceneDef>(Error{"must be a string, the name of a preset"});
        if (!p) return Error{fmt::format("{}: preset: {}", origin, p.error().message)};
        d = std::move(p.value());
    }
    Reader r(origin);
    std::vector<const SceneKey*> given;  // the numbers the file holds, range-checked at the end
    for (const SceneSection& s : scene_sections()) {
        std::vector<std::string_view> allowed;
        for (const SceneKey& k : scene_keys())
            if (k.section() == s.name) allowed.push_back(k.leaf());
        for (const SceneList& l : scene_lists())
            if (l.section() == s.name) allowed.push_back(l.leaf());
        const toml::table* t = &root;
        if (s.name.empty()) {
            allowed.push_back("preset");
            for (const SceneSection& sub : scene_sections())
                if (!sub.name.empty()) allowed.push_back(sub.name);
        } else if (const toml::node* n = root.get(s.name); s.name == "surface" && n && !n->is_table()) {
            // `surface` is either the switch (surface = false) or the table of the
            // smoothing ([surface], whose `enabled` is the same switch).
            if (!n->is_boolean()) r.fail("surface", "must be true or false, or a table ([surface])");
            else d.surface = n->as_boolean()->get();
            continue;
        } else {
            t = r.table(root, s.name);
        }
        if (!t) continue;
        r.allow(*t, s.name.empty() ? "" : std::string(s.name) + ".", allowed);
        for (const SceneKey& k : scene_keys())
            if (k.section() == s.name && r.key(*t, k, d) && k.numeric()) given.push_back(&k);
        for (const SceneList& l : scene_lists())
            if (l.section() == s.name) r.list(*t, l, d);
        if (s.name == "terrain" && t->get("heightmap") && !r.failed()) {
            if (!t->get("source")) d.source.kind = TerrainSource::File;
            std::filesystem::path hp(d.source.heightmap);
            if (hp.is_relative() && !hp.empty())
                d.source.heightmap = (std::filesystem::path(origin).parent_path() / hp).lexically_normal().string();
        }
    }
    if (!r.failed()) apply_solver_scope(root, r, d);
    if (!r.failed()) refuse_irrelevant_keys(root, r, d);
    for (const SceneList& l : scene_lists())  // a list the scene as written never reads
        if (const toml::table* t = root[l.section()].as_table(); t && t->get(l.leaf()) && !l.readers(d))
            r.fail(std::string(l.name), fmt::format("ignored: only {} reads it; remove it", l.readers.text));
    for (const SceneKey* k : given) r.check_range(*k, d);
    if (r.failed()) return Error{r.error()};
    if (d.source.kind == TerrainSource::File && d.source.heightmap.empty())
        return Error{fmt::format("{}: terrain.heightmap: required when terrain.source = \"file\"", origin)};
    if (auto v = validate(d); !v) return Error{fmt::format("{}: {}", origin, v.error().message)};
    return d;
}
}  // namespace

Result<SceneDef> load_scene_file(const std::string& path) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec))
        return Error{fmt::format("{}: scene file not found", path)};
    std::ifstream in(path, std::ios::binary);
    if (!in) return Error{fmt::format("{}: cannot open scene file", path)};
    std::ostringstream ss;
    ss << in.rdbuf();
    return parse_scene_toml(ss.str(), path, default_scene());
}

}  // namespace mr
