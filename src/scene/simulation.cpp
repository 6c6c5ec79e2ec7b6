// The orchestrator of one frame: solver step -> field -> marching cubes.
#include <metariver/scene.h>
#include <metariver/swe_solver.h>

#include "simulation_impl.h"
#include "simulation_internal.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <vector>

namespace mr {

namespace {

using Clock = std::chrono::steady_clock;

/// The seam's term (join_heightfield_to_field) goes from the threshold at the grid's level
/// to 0 this many field radii above it: the height of the skirt around a metaball that
/// rises out of the grid's water (docs/waterfalls.md).
constexpr float kSeamWidth = 1.0f / 3.0f;

double ms_since(Clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Places the spawn volume over the lowest sample of the upstream band (the 10 % of
/// grid rows with the highest z), auto_height above the ground.
Vec3 auto_spawn_center(const Terrain& t, float auto_height) {
    const int band = std::max(1, t.rows() / 10);
    int best_i = t.rows() - 1, best_j = t.columns() / 2;
    float best = t.sample(best_i, best_j);
    for (int i = t.rows() - band; i < t.rows(); ++i) {
        for (int j = 0; j < t.columns(); ++j) {
            if (t.sample(i, j) < best) {
                best = t.sample(i, j);
                best_i = i;
                best_j = j;
            }
        }
    }
    // Step one sample inward from the terrain's edge so the volume sits over ground.
    best_i = std::min(best_i, t.rows() - 2);
    const float s = t.area_scale();
    const float x = static_cast<float>(best_j) * s, z = static_cast<float>(best_i) * s;
    return Vec3(x, t.height_mesh(x, z) + auto_height, z);
}

/// The head of the terrain's main channel (ChannelMap::main_head), one sample in from
/// the edges, auto_height above the ground.
Vec3 channel_spawn_center(const Terrain& t, const ChannelMap& m, float auto_height) {
    auto [i, j] = m.main_head();
    i = std::clamp(i, 1, std::max(1, t.rows() - 2));
    j = std::clamp(j, 1, std::max(1, t.columns() - 2));
    const float s = t.area_scale();
    const float x = static_cast<float>(j) * s, z = static_cast<float>(i) * s;
    return Vec3(x, t.height_mesh(x, z) + auto_height, z);
}

/// Fits an automatically placed source to the terrain: its footprint (disc radius or
/// box half extents) moves inward until it lies inside the rectangle (shrinking only
/// where the terrain is narrower than the source); its height is below.
void fit_auto_source(const Terrain& t, SpawnDef& spawn) {
    const float s = t.area_scale();
    const float margin = 0.25f * s;
    const Vec3 size = t.bounds().extent();
    Vec3& he = spawn.half_extent;
    const bool disc = spawn.shape == SourceShape::Disc, point = spawn.shape == SourceShape::Point;
    // The footprint's half sizes (a disc's radius on both axes), shrunk to the terrain.
    float ex = point ? 0.0f : he.x, ez = point ? 0.0f : (disc ? he.x : he.z);
    ex = std::min(ex, std::max(0.0f, 0.5f * size.x - margin));
    ez = std::min(ez, std::max(0.0f, 0.5f * size.z - margin));
    if (disc) ex = ez = std::min(ex, ez);
    if (!point) {
        he.x = ex;
        he.z = ez;  // a disc's z too: the edge checks read the box of the disc
    }
    const float x0 = t.bounds().min.x, z0 = t.bounds().min.z;
    Vec3& c = spawn.center;
    c.x = std::clamp(c.x, x0 + ex + margin, std::max(x0 + ex + margin, x0 + size.x - ex - margin));
    c.z = std::clamp(c.z, z0 + ez + margin, std::max(z0 + ez + margin, z0 + size.z - ez - margin));
    // auto_height above the ground at the centre, raised where needed so that at least
    // half of the footprint's ground lies a spacing-ish (0.5 m) below the source's
    // bottom: a source over spikes or wedged between steep walls would have no lattice
    // slots, and one raised to the highest ground under it would drop its water from
    // metres up.
    c.y = t.height_mesh(c.x, c.z) + spawn.auto_height;
    std::vector<float> ground;
    const int n = std::max(2, int(std::ceil(2.0f * std::max(ex, ez) / (0.5f * s)))) + 1;
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b) {
            const float x = c.x - ex + 2.0f * ex * float(a) / float(n - 1);
            const float z = c.z - ez + 2.0f * ez * float(b) / float(n - 1);
            if (t.contains_xz(x, z) && (!disc || (x - c.x) * (x - c.x) + (z - c.z) * (z - c.z) <= ex * ex * 1.0001f))
                ground.push_back(t.height_mesh(x, z));
        }
    if (!ground.empty()) {
        std::nth_element(ground.begin(), ground.begin() + ground.size() / 2, ground.end());
        const float bottom = c.y - (point ? 0.0f : he.y);
        float need = ground[ground.size() / 2] + 0.5f;
        // The centre slot's own footprint (a quarter metre around it) is clear too, so
        // even a source on a steep speck of terrain has a slot.
        for (const float dx : {-0.25f, 0.25f})
            for (const float dz : {-0.25f, 0.25f})
                if (t.contains_xz(c.x + dx, c.z + dz)) need = std::max(need, t.height_mesh(c.x + dx, c.z + dz) + 0.5f);
        if (bottom < need) c.y += need - bottom;
    }
}

/// Places an automatic source (auto_center) over the terrain and clears auto_center;
/// returns whether it did.
bool resolve_source(const Terrain& t, const ChannelMap& m, SpawnDef& spawn) {
    if (!spawn.auto_center) return false;
    spawn.center = spawn.auto_channel ? channel_spawn_center(t, m, spawn.auto_height) : auto_spawn_center(t, spawn.auto_height);
    fit_auto_source(t, spawn);
    spawn.auto_center = false;
    return true;
}

/// Radius of the source's footprint, metres: a disc's, or the larger half extent of a box.
float source_footprint(const SpawnDef& spawn) {
    return std::max(spawn.half_extent.x, spawn.shape == SourceShape::Disc ? 0.0f : spawn.half_extent.z);
}

}  // namespace

namespace detail {
/// The main channel from the source: from the main head for the automatic channel
/// source, else from the channel cell nearest the source's centre, to where it leaves.
std::vector<std::pair<int, int>> main_channel_path(const Terrain& t, const ChannelMap& m, const SpawnDef& asked,
                                                   const Vec3& center) {
    if (asked.auto_center && asked.auto_channel) return m.path_from(m.main_head().first, m.main_head().second);
    const float s = t.area_scale();
    // Clamped before rounding: the source is checked against the terrain only later.
    const int i = int(std::lround(std::clamp((center.z - t.bounds().min.z) / s, 0.0f, float(t.rows() - 1))));
    const int j = int(std::lround(std::clamp((center.x - t.bounds().min.x) / s, 0.0f, float(t.columns() - 1))));
    const auto [a, b] = m.nearest_channel_cell(i, j);
    return m.path_from(a, b);
}

}  // namespace detail

Simulation::Impl::Impl(const SceneDef& def, Terrain terrain, Bvh bvh, std::optional<RiverSize> sizing,
                       SolverEntry solver)
    : def_(def),
      terrain_(std::move(terrain)),
      bvh_(std::move(bvh)),
      solver_entry_(std::move(solver)),
      channel_(ChannelMap::build(terrain_)),
      sizing_(sizing) {  // before the prefill, which reads it
    SpawnDef spawn = def_.spawn;
    if (resolve_source(terrain_, channel_, spawn)) def_.spawn = spawn;
    measure_main_channel(def.spawn);
    configure_field();
    // def_.spawn is the resolved source (`spawn`) from here on.
    solver_ = solver_entry_.create(def_, terrain_, bvh_);
    if (!solver_) return;  // create() reports it
    make_foam();
    if (solver_entry_.prefills && def_.spawn.prefill && terrain_.condition_report().mode == TerrainCondition::Carve)
        prefill_channel();
}

void Simulation::Impl::make_foam() {
    foam_.reset();
    heightfield_foam_.reset();
    if (!def_.foam.enabled) return;
    // Particles' foam where the solver has kernel neighbourhoods, the grid's where it has a
    // heightfield; the hybrid has both (its falls throw spray, its pools and reaches foam).
    if (solver_entry_.foam_kernel_radius)
        foam_.emplace(def_.foam, solver_entry_.foam_kernel_radius(def_), def_.integrator.gravity);
    if (solver_->water_heightfield()) heightfield_foam_.emplace(def_.foam);
}

void Simulation::Impl::configure_field() {
    // Compact kernel: the sparse field over the particles' box or the terrain's.
    sparse_def_.kernel = poly6_kernel(def_.field.radius, 1.0f);
    sparse_def_.resolution = def_.field.resolution;
    sparse_def_.bounds_offset = def_.field.bounds_offset;
    if (def_.field.bounds == FieldBounds::Terrain) {
        const Aabb b = terrain_.bounds();
        const float h = 1.0f / def_.field.resolution;
        // In double, clamped: create() refused counts beyond kMaxFieldAxisSamples already.
        const auto samples = [&](float e) {
            return static_cast<int>(std::min(std::ceil(double(e) / double(h)) + 1.0, double(kMaxFieldAxisSamples)));
        };
        sparse_def_.domain = DomainMode::FixedBox;
        sparse_def_.box = SampleGrid{.origin = b.min, .spacing = h, .nx = samples(b.extent().x),
                                     .ny = samples(b.extent().y + 2.0f * def_.field.bounds_offset),
                                     .nz = samples(b.extent().z)};
    } else {
        sparse_def_.domain = DomainMode::BallBounds;
    }
}

float Simulation::Impl::prefill_share() const {
    // The section's rate (size_river before a ceiling lowered it) against the source's:
    // a thinner river than the section starts as thin.
    const float section = detail::section_rate(def_, terrain_.area_scale(), sizing_ ? sizing_->speed : kRiverSpeed);
    const float rate = float(def_.spawn.particles_per_second());
    return section > 0.0f && rate > 0.0f ? std::min(1.0f, rate / section) : 1.0f;
}

void Simulation::Impl::prefill_channel() {
    // kRiverFill of the carved section, moving down the channel at kRiverTransitSpeed,
    // clear of the source's basin (the source fills that), at most half the budget
    // (the rest is the source's until the sink recycles).
    const CarveDef carve = carve_def(def_, terrain_.area_scale());
    const SpawnDef& sp = def_.spawn;
    const ChannelFillDef fd{.spacing = def_.pbf.spacing,
                            .floor_m = carve.floor_m,
                            .depth_m = kRiverFill * carve.depth_m,
                            .clearance_m = def_.collision.radius + def_.collision.offset,
                            .speed = kRiverTransitSpeed,
                            .skip_center = sp.center,
                            .skip_radius_m = source_footprint(sp) + 2.0f * def_.pbf.spacing,
                            .most = size_t(std::max(sp.count, 0)) / 2,
                            .share = prefill_share()};
    const ChannelFill fill = fill_channel(terrain_, main_path_, fd);
    solver_->place(fill.position, fill.velocity);
    prefilled_ = fill.position.size();
}

std::vector<std::string> Simulation::Impl::warnings() const {
    std::vector<std::string> w = scene_warnings(def_);
    if (sizing_ && sizing_->capped)
        w.push_back(fmt::format("particles.count: the main channel is {:.0f} m long; at {} particles (the most the "
                                "automatic budget takes) the river runs at {:.1f} particles per second, thinner than its "
                                "channel; set particles.count and particles.flow_rate, or a larger pbf.spacing",
                                sizing_->channel_length_m, def_.spawn.count, def_.spawn.particles_per_second()));
    for (std::string& s : solver_->warnings()) w.push_back(std::move(s));
    return w;
}

Result<std::unique_ptr<Simulation>> Simulation::create(const SceneDef& def, const SolverRegistry& solvers) {
    if (auto e = solvers.find(def.solver); !e) return e.error();
    if (auto v = validate(def); !v) return v.error();
    auto map = load_scene_heightmap(def);
    if (!map) return map.error();
    return create(def, map.value(), solvers);
}

bool smoothing_on(const SceneDef& def) {
    return def.surface && def.smoothing.method != SmoothingMethod::None && def.smoothing.iterations > 0;
}

float flow_radius(const SceneDef& def) {
    // A compact field is > threshold > 0 only within its support of some particle: every
    // vertex of the extracted surface has a particle within field.radius (smoothing moves
    // vertices by a fraction of a cell). The paper's kernels reach everywhere; their
    // surface lies within about one metaball radius of the balls, so twice that is used.
    return def.field.kernel == FieldKernel::Poly6 ? def.field.radius : 2.0f * def.field.radius;
}

SmoothingGround smoothing_ground(const Terrain& t) {
    return {.vertices = t.vertices().data(), .columns = t.columns(), .rows = t.rows(), .spacing = t.area_scale()};
}

namespace detail {
Status rain_mask_readable(const SceneDef& d) {
    if ((d.solver != SolverKind::Swe && d.solver != SolverKind::Hybrid) || d.swe.rain_mask.empty()) return Ok{};
    if (auto m = load_rain_mask(d.swe.rain_mask, 1, 1); !m) return m.error();
    return Ok{};
}

/// field.bounds = "terrain": the fixed field box spans the terrain, and its samples per
/// axis must fit an int (4096 samples x 1e4 m x 64 per metre would not).
Status field_box_fits(const FieldDef& f, const Terrain& t) {
    if (f.bounds != FieldBounds::Terrain) return Ok{};
    const Vec3 e = t.bounds().extent() + Vec3(0.0f, 2.0f * f.bounds_offset, 0.0f);
    const double most = double(std::max({e.x, e.y, e.z})) * double(f.resolution) + 1.0;
    if (!(most <= double(kMaxFieldAxisSamples)))
        return Error{fmt::format("field.resolution: with field.bounds = \"terrain\" the field would have {:.3g} "
                                 "samples along the terrain's longest side; at most {} (lower field.resolution "
                                 "or terrain.area_scale, or use field.bounds = \"particles\")",
                                 most, kMaxFieldAxisSamples)};
    return Ok{};
}
}  // namespace detail

Result<std::unique_ptr<Simulation>> Simulation::create(const SceneDef& def, const Heightmap& map,
                                                       const SolverRegistry& solvers) {
    const auto entry = solvers.find(def.solver);
    if (!entry) return entry.error();
    if (auto v = validate(def); !v) return v.error();
    if (auto m = detail::rain_mask_readable(def); !m) return m.error();
    SceneDef resolved = def;
    resolved.terrain.condition = resolved_condition(def);
    resolved.pbf.sleep_threshold = resolved_sleep_threshold(def);
    resolved.pbf.damping = resolved_damping(def);
    resolved.pbf.contact_band = resolved_contact_band(def);
    resolved.pbf.wall_density = resolved_wall_density(def);
    auto terrain = Terrain::build(map, resolved.terrain);
    if (!terrain) return terrain.error();
    const bool auto_size = def.solver == SolverKind::Pbf && (def.spawn.count == kAutoCount || def.spawn.auto_rate());
    std::optional<RiverSize> sizing;
    if (resolved.terrain.condition == TerrainCondition::Carve || auto_size) {
        // The main channel of the breached terrain from where the source will sit, and
        // a basin under the source (resolved as the constructor will: x and z do not
        // depend on the heights the carve changes).
        const ChannelMap m = ChannelMap::build(terrain.value());
        SpawnDef spawn = def.spawn;
        resolve_source(terrain.value(), m, spawn);
        auto path = detail::main_channel_path(terrain.value(), m, def.spawn, spawn.center);
        if (auto_size) {
            const float as = terrain->area_scale();
            float length = 0.0f;
            for (size_t k = 1; k < path.size(); ++k)
                length += as * std::hypot(float(path[k].first - path[k - 1].first), float(path[k].second - path[k - 1].second));
            if (path.size() < 2) length = std::hypot(terrain->bounds().extent().x, terrain->bounds().extent().z);
            // The mean ground slope from the head to the outlet, on the breached terrain.
            const float slope = path.size() < 2 || !(length > 0.0f)
                                    ? 1.0f
                                    : (terrain->sample(path.front().first, path.front().second) -
                                       terrain->sample(path.back().first, path.back().second)) / length;
            // (auto_size: a PBF river.) The river's spacing for this terrain, when "auto".
            const float d = def.pbf.auto_spacing ? auto_spacing(def, terrain.value()) : def.pbf.spacing;
            resolved.pbf.auto_spacing = false;
            if (d != def.pbf.spacing) {
                // The river's lengths at the spacing this terrain asks for; the source is
                // placed again at its scaled size, and the path from where it now sits.
                scale_river_lengths(resolved, d);
                spawn = resolved.spawn;
                resolve_source(terrain.value(), m, spawn);
                path = detail::main_channel_path(terrain.value(), m, resolved.spawn, spawn.center);
            }
            const RiverSize size = size_river(resolved, as, length, slope);
            sizing = size;
            if (def.spawn.count == kAutoCount) resolved.spawn.count = size.count;
            if (def.spawn.auto_rate())  // in the unit flow_rate is given in
                resolved.spawn.flow_rate =
                    def.spawn.litres_per_particle > 0.0f ? size.rate * def.spawn.litres_per_particle : size.rate;
        }
        if (resolved.terrain.condition == TerrainCondition::Carve) {
            CarveDef carve = carve_def(resolved, terrain->area_scale());
            carve.basin_center = spawn.center;
            carve.basin_radius_m =
                spawn.shape == SourceShape::Point ? 0.0f : source_footprint(spawn) + detail::carve_spacing_of(resolved);
            // Off the map's edges by the section's half width and the levee (1.5 samples).
            const float as = terrain->area_scale();
            const int margin = int(std::ceil((0.5f * carve.width_m) / as + 1.5f));
            terrain->carve_channel(keep_off_edges(path, terrain->rows(), terrain->columns(), margin), carve);
            // The source stays where the carve was cut for it. Placed again on the carved
            // ground, the main head moved elsewhere on some terrains (the carve changes
            // the flow accumulation), and the river ran down an uncarved path while the
            // carved channel stayed dry (colorado_rockies: a 1-sample breach with sills
            // 4 m high at the diagonal steps; nothing reached the outlet in 120 s).
            if (def.spawn.auto_center) {
                resolved.spawn.center = spawn.center;
                resolved.spawn.half_extent = spawn.half_extent;
                resolved.spawn.auto_center = false;
                fit_auto_source(terrain.value(), resolved.spawn);  // its height over the carved basin
            }
        }
    }
    // Not a PBF river: the budget the default scene had before it sized itself.
    if (resolved.spawn.count == kAutoCount) resolved.spawn.count = kFixedDefaultCount;
    if (resolved.spawn.auto_rate()) resolved.spawn.flow_rate = 0.0f;  // not a PBF river: no continuous source
    if (auto f = detail::field_box_fits(resolved.field, terrain.value()); !f) return f.error();
    auto bvh = Bvh::build(terrain.value(), BvhDef{.leaf_triangles = def.collision.leaf_triangles});
    if (!bvh) return bvh.error();
    std::unique_ptr<Simulation> sim(new Simulation(
        std::make_unique<Impl>(resolved, std::move(terrain.value()), std::move(bvh.value()), sizing, *entry.value())));
    if (!sim->impl_->solver_) return Error{fmt::format("solver: \"{}\"'s factory built no solver", def.solver.name)};
    if (auto b = sim->impl_->add_scene_bodies(resolved.bodies); !b) return b.error();
    if (auto v = validate_on_terrain(sim->def(), sim->terrain()); !v) return v.error();  // resolved source
    sim->impl_->requested_ = def;
    return sim;
}

void Simulation::Impl::step(float frame_dt) {
    const auto t0 = Clock::now();
    solver_->step_frame(frame_dt);
    step_grid_bodies(frame_dt);
    timings_.simulate_ms = ms_since(t0);
    step_foam(frame_dt);
    if (!def_.surface) {
        timings_.field_ms = timings_.surface_ms = timings_.smoothing_ms = 0.0;
        smooth_ws_.stats = SmoothingStats{};
        return;
    }
    // The surface from what the solver gives: particles, a heightfield, or both (one mesh).
    seam_.clear();
    seam_velocity_.clear();
    if (const Particles* p = solver_->water_particles()) {
        build_particle_surface(*p);
    } else {
        surface_.clear();
        heightfield_velocity_.clear();
        timings_.field_ms = timings_.surface_ms = timings_.smoothing_ms = 0.0;
        smooth_ws_.stats = SmoothingStats{};
    }
    if (const HeightfieldWater* w = solver_->water_heightfield()) append_heightfield(*w);
}

void Simulation::Impl::step_foam(float frame_dt) {
    const Particles* p = solver_->water_particles();
    const HeightfieldWater* w = solver_->water_heightfield();
    const auto t0 = Clock::now();
    if (heightfield_foam_ && w) heightfield_foam_->step(*w, terrain_.vertices(), frame_dt, solver_->frame());
    if (foam_ && p) {
        const float dt = def_.integrator.fixed_dt > 0.0f ? def_.integrator.fixed_dt : frame_dt;
        foam_->step(*p, terrain_, dt, solver_->frame());
        // The hybrid: spray that fell into the grid's water floats on it as the grid's foam.
        if (heightfield_foam_ && w) heightfield_foam_->take_landed(*foam_, *w, terrain_.vertices());
    }
    if (foam_ || heightfield_foam_) timings_.foam_ms = ms_since(t0);
}

void Simulation::Impl::build_particle_surface(const Particles& p) {
    auto t0 = Clock::now();
    p.gather_active_positions(balls_);
    if (def_.field.kernel == FieldKernel::Poly6) {
        // Particles spread over kilometres: the field around the most of them, the rest not drawn.
        if (sparse_def_.domain == DomainMode::BallBounds) {
            const size_t left_out = keep_balls_within_cap(balls_, sparse_def_.resolution, sparse_def_.bounds_offset,
                                                          sparse_def_.max_samples);
            field_windows_ += left_out > 0;
            field_left_out_ = std::max(field_left_out_, left_out);
        }
        if (auto b = sparse_.build(balls_, sparse_def_); !b) {
            ++field_overflows_;
            field_overflow_message_ = b.error().message;
        }
        // Both kinds of water (hybrid): the grid's surface joins the metaballs' in the field.
        if (const HeightfieldWater* w = solver_->water_heightfield())
            join_heightfield_to_field(terrain_.vertices(), w->depth, w->rows, w->columns, def_.field.threshold,
                                      kSeamWidth * def_.field.radius, sparse_, seam_);
        timings_.field_ms = ms_since(t0);
        t0 = Clock::now();
        extract_surface_sparse(sparse_, def_.field.threshold, surface_, surface_ws_);
        const SmoothingField weights{.field = &sparse_, .kernel = sparse_def_.kernel, .threshold = def_.field.threshold};
        const SmoothingGround ground = smoothing_ground(terrain_);
        const auto ts = Clock::now();
        smooth_surface(surface_, def_.smoothing, smooth_ws_, &weights, &ground);
        timings_.smoothing_ms = ms_since(ts);
        // What lies under the water is never seen; the flat water the field draws flows as
        // the grid's around it (the flow detail).
        if (const HeightfieldWater* w = solver_->water_heightfield(); w && seam_.columns > 0) {
            drop_under_water(terrain_.vertices(), w->depth, w->rows, w->columns, seam_, surface_, seam_scratch_);
            seam_grid_velocities(terrain_.vertices(), w->depth, w->velocity, w->rows, w->columns,
                                 kSeamWidth * def_.field.radius, surface_.positions, seam_velocity_);
        }
        timings_.surface_ms = ms_since(t0);
        return;
    }
    if (!compute_field_paper(balls_, def_.field, field_)) {
        ++field_overflows_;
        field_overflow_message_ = fmt::format("the field's grid around the particles would have more than {} samples",
                                              kMaxFieldSamples);
    }
    timings_.field_ms = ms_since(t0);

    t0 = Clock::now();
    extract_surface(field_, def_.field.threshold, surface_);
    const SmoothingGround ground = smoothing_ground(terrain_);
    const auto ts = Clock::now();
    smooth_surface(surface_, def_.smoothing, smooth_ws_, nullptr, &ground);  // the paper's kernels: no feature weights
    timings_.smoothing_ms = ms_since(ts);
    timings_.surface_ms = ms_since(t0);
}

void Simulation::Impl::append_heightfield(const HeightfieldWater& w) {
    // On the terrain's grid: each vertex is its bed sample raised by the depth.
    const auto t0 = Clock::now();
    heightfield_velocity_.clear();
    append_heightfield_surface(terrain_.vertices(), w.depth, w.rows, w.columns, surface_, &heightfield_scratch_,
                               w.velocity, &heightfield_velocity_, seam_.cell, w.wet_first, w.wet_last);
    timings_.surface_ms += ms_since(t0);
}

std::array<int, 3> Simulation::Impl::field_dims() const {
    if (def_.field.kernel == FieldKernel::Poly6) {
        const SampleGrid& g = sparse_.grid();
        return {g.nx, g.ny, g.nz};
    }
    return {field_.nx, field_.ny, field_.nz};
}

float Simulation::Impl::wet_fraction() const {
    const Particles& p = particles();
    const WetChannelDef wet{.width = std::max(3.0f, 3.0f * terrain_.area_scale()), .depth = 3.0f};
    return wet_channel_fraction(terrain_, channel(), p.position, p.active, wet);
}

float Simulation::Impl::channel_coverage() const {
    refresh_channel();
    const Particles& p = particles();
    const HeightfieldWater* w = solver_->water_heightfield();
    if (p.size() == 0 && w) return coverage_.measure(*w, def_.swe.dry_depth);  // swe: its wet cells
    return coverage_.measure(p.position, p.active);
}

float Simulation::Impl::spray_fraction() const {
    const SprayScale scale = solver_entry_.spray_scale ? solver_entry_.spray_scale(def_) : SprayScale{};
    const Particles& p = particles();
    return mr::spray_fraction(terrain_, p.position, p.active, scale.kernel_radius, scale.spacing);
}

std::vector<double> Simulation::active_speeds() const {
    const Particles& p = particles();
    std::vector<double> speeds;
    speeds.reserve(p.size());
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i]) speeds.push_back(static_cast<double>(glm::length(p.velocity[i])));
    return speeds;
}

uint64_t Simulation::Impl::state_hash() const {
    uint64_t h = 1469598103934665603ull;
    auto mix = [&h](const void* data, size_t n) {
        const auto* b = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < n; ++i) {
            h ^= b[i];
            h *= 1099511628211ull;
        }
    };
    const Particles& p = particles();
    mix(p.position.data(), p.position.size() * sizeof(Vec3));
    mix(p.velocity.data(), p.velocity.size() * sizeof(Vec3));
    mix(p.active.data(), p.active.size());
    if (const HeightfieldWater* w = solver_->water_heightfield()) {
        mix(w->depth.data(), w->depth.size() * sizeof(float));
        mix(w->velocity.data(), w->velocity.size() * sizeof(Vec3));
    }
    for (const BodyState& b : bodies()) {  // none: the hash of the water alone, as before bodies
        mix(&b.id, sizeof(b.id));
        mix(&b.position, sizeof(b.position));
        mix(&b.orientation, sizeof(b.orientation));
        mix(&b.velocity, sizeof(b.velocity));
        mix(&b.angular_velocity, sizeof(b.angular_velocity));
    }
    return h;
}

}  // namespace mr
