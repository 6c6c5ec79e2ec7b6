// The "swe" solver (include/metariver/swe_solver.h): the shallow-water core
// (src/swe/shallow_water.h) on the terrain's grid, shown as a HeightfieldWater.
#include <metariver/swe_solver.h>
#include <metariver/terrain.h>

#include "shallow_water.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr {

namespace {

constexpr double kMmPerHour = 1e-3 / 3600.0;  // m/s

swe::ShallowWaterDef core_def(const SweDef& d, double gravity) {
    swe::ShallowWaterDef c;
    c.gravity = gravity;
    c.cfl = std::clamp(static_cast<double>(d.cfl), 1e-3, 0.5);
    c.dry_depth = std::max(static_cast<double>(d.dry_depth), 0.0);
    c.manning = std::max(static_cast<double>(d.manning), 0.0);
    c.second_order = d.second_order;
    c.west = c.east = c.south = c.north = {swe::EdgeKind::Open};
    return c;
}

}  // namespace

SweSolver::SweSolver(const Terrain& terrain, const SweDef& def, Vec3 resolved_source, float gravity)
    : def_(def), source_(resolved_source) {
    const int nx = std::max(terrain.columns(), 1), ny = std::max(terrain.rows(), 1);
    const std::span<const Vec3> v = terrain.vertices();
    std::vector<double> bed(static_cast<size_t>(nx) * ny, 0.0);
    for (size_t k = 0; k < bed.size() && k < v.size(); ++k) bed[k] = v[k].y;
    water_.rows = ny;
    water_.columns = nx;
    water_.origin = v.empty() ? Vec3(0.0f) : v.front();
    water_.spacing = terrain.area_scale();
    water_.depth.assign(water_.size(), 0.0f);
    water_.velocity.assign(water_.size(), Vec3(0.0f));
    core_ = std::make_unique<swe::ShallowWater>(nx, ny, water_.spacing, bed, core_def(def_, gravity > 0.0f && std::isfinite(gravity) ? gravity : 9.81));
    if (std::isfinite(def_.initial_level))
        for (int j = 0; j < ny; ++j) {
            if (std::isfinite(def_.dam_z) && water_.origin.z + static_cast<float>(j) * water_.spacing < def_.dam_z) continue;
            for (int i = 0; i < nx; ++i) core_->set_state(i, j, std::max(def_.initial_level - bed[static_cast<size_t>(j) * nx + i], 0.0));
        }
    core_->balance_reset();
    apply_def();
    publish();
}

SweSolver::~SweSolver() = default;

void SweSolver::apply_def() {
    core_->set_def(core_def(def_, core_->def().gravity));
    core_->set_rain(std::max(static_cast<double>(def_.rain), 0.0) * kMmPerHour);
    const Vec3 c = def_.auto_source ? source_ : def_.source_center;
    source_i_ = static_cast<int>(std::lround((c.x - water_.origin.x) / water_.spacing));
    source_j_ = static_cast<int>(std::lround((c.z - water_.origin.z) / water_.spacing));
    const bool inside = source_i_ >= 0 && source_j_ >= 0 && source_i_ < water_.columns && source_j_ < water_.rows;
    std::vector<swe::PointSource> sources;
    if (def_.discharge > 0.0f && inside) sources.push_back({source_i_, source_j_, def_.discharge});
    core_->set_sources(std::move(sources));
}

bool SweSolver::set_params(const SweDef& def, Vec3 resolved_source) {
    const bool same_lake = std::isnan(def.initial_level) ? std::isnan(def_.initial_level) : def.initial_level == def_.initial_level;
    const bool same_dam = std::isnan(def.dam_z) ? std::isnan(def_.dam_z) : def.dam_z == def_.dam_z;
    if (!same_lake || !same_dam) return false;
    def_ = def;
    source_ = resolved_source;
    apply_def();
    return true;
}

void SweSolver::publish() {
    // The float view of the core's doubles (depth and depth-averaged velocity).
    float fastest = 0.0f;
    for (int j = 0; j < water_.rows; ++j)
        for (int i = 0; i < water_.columns; ++i) {
            const size_t k = static_cast<size_t>(j) * water_.columns + i;
            const double h = core_->depth(i, j);
            water_.depth[k] = static_cast<float>(h);
            const bool moving = h > core_->def().dry_depth;
            water_.velocity[k] = moving ? Vec3(static_cast<float>(core_->discharge_x(i, j) / h), 0.0f,
                                               static_cast<float>(core_->discharge_y(i, j) / h))
                                        : Vec3(0.0f);
            fastest = std::max(fastest, glm::length(water_.velocity[k]));
        }
    counters_.max_speed = fastest;
}

void SweSolver::step_frame(float frame_dt) {
    const uint64_t before = core_->stats().substeps;
    if (frame_dt > 0.0f && std::isfinite(frame_dt)) core_->advance(frame_dt);
    last_substeps_ = core_->stats().substeps - before;
    counters_.substeps = core_->stats().substeps;
    counters_.cell_updates = core_->stats().cell_updates;
    ++frame_;
    publish();
}

SweBalance SweSolver::balance() const {
    const swe::MassBalance b = core_->balance();
    return {b.initial, b.inflow, b.rain, b.outflow, b.stored};
}

std::vector<std::string> SweSolver::warnings() const {
    std::vector<std::string> w;
    if (def_.discharge > 0.0f && (source_i_ < 0 || source_j_ < 0 || source_i_ >= water_.columns || source_j_ >= water_.rows))
        w.push_back(fmt::format("swe.source_center: ({}, {}) lies outside the terrain; swe.discharge pours nothing",
                                def_.auto_source ? source_.x : def_.source_center.x, def_.auto_source ? source_.z : def_.source_center.z));
    return w;
}

}  // namespace mr
