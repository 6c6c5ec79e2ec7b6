// The "swe" solver's interaction (include/metariver/swe_solver.h): pour, push, rain set
// per cell and the sculpted bed, on the core's cells (cell (i, j): column i along x, row j along z).
#include <metariver/swe_solver.h>
#include <metariver/terrain.h>

#include "shallow_water.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr {

namespace {

/// (1 - (d / r)^2)^2 for d < r, else 0.
double falloff(double d2, double r2) {
    const double q = 1.0 - d2 / r2;
    return q > 0.0 ? q * q : 0.0;
}

}  // namespace

void SweSolver::pour(const Vec3& center, int count) {
    if (count <= 0 || !std::isfinite(center.x + center.z)) return;
    const double s = water_.spacing, r = kPourRadius * s, r2 = r * r;
    const double cx = (center.x - water_.origin.x) / s, cz = (center.z - water_.origin.z) / s;
    const int i0 = std::max(int(std::floor(cx - kPourRadius)), 0), i1 = std::min(int(std::ceil(cx + kPourRadius)), water_.columns - 1);
    const int j0 = std::max(int(std::floor(cz - kPourRadius)), 0), j1 = std::min(int(std::ceil(cz + kPourRadius)), water_.rows - 1);
    double total = 0.0;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) total += falloff(s * s * ((i - cx) * (i - cx) + (j - cz) * (j - cz)), r2);
    if (!(total > 0.0)) return;  // the centre off the map
    const double volume = double(count) * kPourVolume;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            const double w = falloff(s * s * ((i - cx) * (i - cx) + (j - cz) * (j - cz)), r2) / total;
            if (w <= 0.0) continue;
            const double h = core_->depth(i, j);
            // The poured water at rest: the cell's momentum kept, its depth raised.
            core_->set_state(i, j, h + w * volume / (s * s), core_->discharge_x(i, j), core_->discharge_y(i, j));
        }
    poured_ += volume;
    publish();
}

void SweSolver::set_spawn_center(const Vec3& center) {
    if (center == source_ || !std::isfinite(center.x + center.z)) return;  // (a sculpt passes the same centre)
    source_ = center;
    if (def_.auto_source) apply_def();
}

size_t SweSolver::push(const Vec3& center, float radius, const Vec3& velocity) {
    if (!(radius > 0.0f) || !std::isfinite(center.x + center.z + velocity.x + velocity.z)) return 0;
    const double s = water_.spacing, r2 = double(radius) * radius, reach = radius / s;
    const double cx = (center.x - water_.origin.x) / s, cz = (center.z - water_.origin.z) / s;
    const int i0 = std::max(int(std::floor(cx - reach)), 0), i1 = std::min(int(std::ceil(cx + reach)), water_.columns - 1);
    const int j0 = std::max(int(std::floor(cz - reach)), 0), j1 = std::min(int(std::ceil(cz + reach)), water_.rows - 1);
    size_t pushed = 0;
    for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
            const double h = core_->depth(i, j), w = falloff(s * s * ((i - cx) * (i - cx) + (j - cz) * (j - cz)), r2);
            if (w <= 0.0 || h <= core_->def().dry_depth) continue;
            core_->set_state(i, j, h, core_->discharge_x(i, j) + h * w * velocity.x, core_->discharge_y(i, j) + h * w * velocity.z);
            ++pushed;
        }
    if (pushed) publish();
    return pushed;
}

Status SweSolver::set_rain(std::span<const float> mm_per_h) {
    if (!mm_per_h.empty() && mm_per_h.size() != water_.size())
        return Error{fmt::format("mm_per_h: {} values for a grid of {} cells ({} rows x {} columns; none: the scene's "
                                 "rain)", mm_per_h.size(), water_.size(), water_.rows, water_.columns)};
    for (size_t k = 0; k < mm_per_h.size(); ++k)
        if (!(mm_per_h[k] >= 0.0f && mm_per_h[k] <= kMaxRainRate))  // NaN fails too
            return Error{fmt::format("mm_per_h[{}] (row {}, column {}): must be in [0, {}] mm/h (got {})", k,
                                     k / size_t(water_.columns), k % size_t(water_.columns), kMaxRainRate, mm_per_h[k])};
    rain_rates_.assign(mm_per_h.begin(), mm_per_h.end());
    apply_rain();
    return Ok{};
}

void SweSolver::terrain_edited(const Terrain& terrain, int i0, int i1, int j0, int j1) {
    // Terrain rows i are the core's j, its columns j the core's i.
    const std::span<const Vec3> v = terrain.vertices();
    for (int row = std::max(i0, 0); row <= std::min(i1, water_.rows - 1); ++row)
        for (int col = std::max(j0, 0); col <= std::min(j1, water_.columns - 1); ++col)
            core_->set_bed(col, row, v[size_t(row) * size_t(water_.columns) + size_t(col)].y);
    publish();
}

}  // namespace mr
