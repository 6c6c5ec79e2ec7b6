// Drainage conditioning (see terrain.h).
//
// Both modes flood from the terrain's edge inwards in order of height (priority_flood.h,
// the drainage network's flood too; ties by cell index, so the result is deterministic):
//  - Fill: R. Barnes, C. Lehman, D. Mulla, "Priority-Flood: An optimal depression-
//    filling and watershed-labeling algorithm for digital elevation models", Computers
//    & Geosciences 62, 2014 (the epsilon variant, with the epsilon a slope): a cell
//    reached from a higher-or-equal cell is raised just above it.
//  - Breach: J. Lindsay, "Efficient hybrid breaching-filling sink removal methods for
//    flow path enforcement in digital elevation models", Hydrological Processes 30,
//    2016 (complete breaching on the priority-flood tree): when the flood reaches a cell
//    lower than the cell it came from, the path back to the edge is lowered until it
//    descends all the way, carving a channel through the depression's rim.
// Heights are worked in double so the slope survives large elevations.
#include <metariver/terrain.h>

#include "priority_flood.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace mr {

std::string_view to_string(TerrainCondition c) {
    switch (c) {
        case TerrainCondition::None: return "none";
        case TerrainCondition::Fill: return "fill";
        case TerrainCondition::Breach: return "breach";
        case TerrainCondition::Carve: return "carve";
        case TerrainCondition::Auto: return "auto";
    }
    return "?";
}

ConditionReport condition_heights(std::vector<float>& heights, int columns, int rows, float area_scale,
                                  TerrainCondition mode) {
    ConditionReport rep;
    rep.mode = mode;
    const size_t n = size_t(columns) * size_t(rows);
    if (mode == TerrainCondition::None || mode == TerrainCondition::Auto || columns < 2 || rows < 2 || heights.size() != n) return rep;
    std::vector<double> h(heights.begin(), heights.end());
    const double eps_straight = double(kConditionSlope) * area_scale;
    const double eps_diagonal = eps_straight * std::sqrt(2.0);
    std::vector<int64_t> parent(n, -1);
    priority_flood(h, rows, columns, [&](size_t c, size_t nb, bool diagonal) {
        parent[nb] = int64_t(c);
        const double eps = diagonal ? eps_diagonal : eps_straight;
        if (!(h[nb] < h[c] + eps)) return;  // (not >=: a NaN height is left as it is)
        if (mode == TerrainCondition::Fill) {  // (Carve breaches here; the scene carves later)
            h[nb] = h[c] + eps;
            return;
        }
        // Lower the flood path from c back to the edge until it descends from nb by at
        // least the slope at every step.
        double below = h[nb];
        size_t child = nb;
        int64_t p = int64_t(c);
        while (p >= 0) {
            const size_t pc = size_t(p);
            const bool diag = (pc / size_t(columns) != child / size_t(columns)) &&
                              (pc % size_t(columns) != child % size_t(columns));
            const double want = below - (diag ? eps_diagonal : eps_straight);
            if (h[pc] <= want) break;
            h[pc] = want;
            below = want;
            child = pc;
            p = parent[pc];
        }
    });
    const double cell_area = double(area_scale) * double(area_scale);
    for (size_t k = 0; k < n; ++k) {
        const float v = float(h[k]);
        const double d = double(v) - double(heights[k]);
        if (d > 0.0) ++rep.cells_raised;
        if (d < 0.0) ++rep.cells_lowered;
        rep.max_change_m = std::max(rep.max_change_m, float(std::abs(d)));
        rep.volume_m3 += std::abs(d) * cell_area;
        heights[k] = v;
    }
    return rep;
}

void Terrain::carve_channel(std::span<const std::pair<int, int>> path, const CarveDef& def) {
    if (path.empty() || !(def.width_m > 0.0f) || !(def.depth_m > 0.0f)) return;
    if (given_heights_.empty()) {
        given_heights_.resize(vertices_.size());
        for (size_t k = 0; k < vertices_.size(); ++k) given_heights_[k] = vertices_[k].y;
    }
    const double s = area_scale_, half = 0.5 * double(def.width_m), depth = def.depth_m;
    const double inner = std::clamp(0.5 * double(def.floor_m), 0.0, half);  // the flat bed's half width
    auto inside = [&](int i, int j) { return i >= 0 && j >= 0 && i < rows_ && j < columns_; };
    // The ground under the path as it was before this carve (a path cell beside the
    // previous one is already in that one's cross-section).
    std::vector<float> before(vertices_.size());
    for (size_t k = 0; k < vertices_.size(); ++k) before[k] = vertices_[k].y;
    // The path's mean slope (ground at the head to ground at the outlet over the path's
    // length), for the steepest drop below.
    double length = 0.0, head_ground = 0.0, end_ground = 0.0;
    {
        std::pair<int, int> a{-1, -1};
        for (const auto& [pi, pj] : path) {
            if (!inside(pi, pj)) continue;
            if (a.first < 0) head_ground = before[size_t(pi) * columns_ + pj];
            else length += s * std::hypot(double(pi - a.first), double(pj - a.second));
            end_ground = before[size_t(pi) * columns_ + pj];
            a = {pi, pj};
        }
    }
    const double mean_slope = length > 0.0 ? (head_ground - end_ground) / length : 0.0;
    // The bed's least slope, kCarveLeastSlope: water crosses a flat reach at walking pace
    // instead of creeping over it and falling asleep.
    const double slope = kCarveLeastSlope;
    double bed = 0.0;
    std::pair<int, int> prev{-1, -1};
    // Lowers every sample within `half` metres of (cx, cz) (metres) to its parabola.
    auto lower_around = [&](double cx, double cz, double floor, double half) {
        const int r = int(std::ceil(half / s)), ci = int(std::lround(cz / s)), cj = int(std::lround(cx / s));
        for (int i = ci - r; i <= ci + r; ++i)
            for (int j = cj - r; j <= cj + r; ++j) {
                if (!inside(i, j)) continue;
                const double d = std::hypot(double(j) * s - cx, double(i) * s - cz);
                if (d > half) continue;
                const double u = std::max(0.0, (d - inner) / std::max(half - inner, 1e-9));
                float& y = vertices_[size_t(i) * columns_ + j].y;
                y = std::min(y, float(floor + depth * u * u));
            }
    };
    // Pass 1 finds the beds; pass 2 raises levees (bed + depth) on the samples just
    // outside the banks where the ground is lower, pass 3 lowers the channel, so a
    // levee never stands in the channel of a neighbouring path cell.
    std::vector<std::tuple<double, double, double>> beds;  // (x, z, bed)
    for (const auto& [pi, pj] : path) {
        if (!inside(pi, pj)) continue;
        const double ground = before[size_t(pi) * columns_ + pj];
        if (prev.first < 0) {
            bed = ground - depth;
        } else {
            const double step = s * std::hypot(double(pi - prev.first), double(pj - prev.second));
            bed = std::min(ground - depth, bed - slope * step);
        }
        prev = {pi, pj};
        beds.emplace_back(double(pj) * s, double(pi) * s, bed);
    }
    if (beds.empty()) return;
    // No drop steeper than kCarveSteepest (or 1.5 x the path's mean slope on a terrain that
    // steep throughout): where the ground falls off a cliff, the bed upstream of it is
    // cut down into a ramp of that slope, from the cliff's foot back up.
    const double steepest = std::max(double(kCarveSteepest), 1.5 * mean_slope);
    for (size_t k = beds.size() - 1; k-- > 0;) {
        auto& [x, z, b] = beds[k];
        const auto& [nx, nz, nb] = beds[k + 1];
        b = std::min(b, nb + steepest * std::hypot(nx - x, nz - z));
    }
    const double levee = half + 1.5 * s;
    for (const auto& [x, z, b] : beds) {
        const int r = int(std::ceil(levee / s)), ci = int(std::lround(z / s)), cj = int(std::lround(x / s));
        for (int i = ci - r; i <= ci + r; ++i)
            for (int j = cj - r; j <= cj + r; ++j) {
                if (!inside(i, j)) continue;
                const double d = std::hypot(double(j) * s - x, double(i) * s - z);
                if (d <= half || d > levee) continue;
                float& y = vertices_[size_t(i) * columns_ + j].y;
                y = std::max(y, float(b + depth));
            }
    }
    // The source's basin: its bottom is the head's bed, so it drains into the channel.
    if (def.basin_radius_m > 0.0f)
        lower_around(def.basin_center.x, def.basin_center.z, std::get<2>(beds.front()),
                     std::max(half, double(def.basin_radius_m)));
    for (const auto& [x, z, b] : beds) lower_around(x, z, b, half);
    condition_.mode = TerrainCondition::Carve;
    update_condition_report();
}

void Terrain::update_condition_report() {
    condition_.cells_raised = condition_.cells_lowered = 0;
    condition_.max_change_m = 0.0f;
    condition_.volume_m3 = 0.0;
    const double cell_area = double(area_scale_) * double(area_scale_);
    for (size_t k = 0; k < vertices_.size(); ++k) {
        const double d = double(vertices_[k].y) - double(given_heights_[k]);
        if (d > 0.0) ++condition_.cells_raised;
        if (d < 0.0) ++condition_.cells_lowered;
        condition_.max_change_m = std::max(condition_.max_change_m, float(std::abs(d)));
        condition_.volume_m3 += std::abs(d) * cell_area;
    }
    recompute_bounds();
}

}  // namespace mr
