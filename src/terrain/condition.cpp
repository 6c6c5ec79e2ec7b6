// Drainage conditioning (see terrain.h).
//
// Both modes flood from the terrain's edge inwards in order of height (a priority
// queue; ties by cell index, so the result is deterministic):
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

#include <algorithm>
#include <cmath>
#include <functional>
#include <queue>
#include <tuple>

namespace mr {

std::string_view to_string(TerrainCondition c) {
    switch (c) {
        case TerrainCondition::None: return "none";
        case TerrainCondition::Fill: return "fill";
        case TerrainCondition::Breach: return "breach";
    }
    return "?";
}

ConditionReport condition_heights(std::vector<float>& heights, int columns, int rows, float area_scale,
                                  TerrainCondition mode) {
    ConditionReport rep;
    rep.mode = mode;
    const size_t n = size_t(columns) * size_t(rows);
    if (mode == TerrainCondition::None || columns < 2 || rows < 2 || heights.size() != n) return rep;
    std::vector<double> h(heights.begin(), heights.end());
    const double eps_straight = double(kConditionSlope) * area_scale;
    const double eps_diagonal = eps_straight * std::sqrt(2.0);
    std::vector<uint8_t> closed(n, 0);
    std::vector<int64_t> parent(n, -1);
    using Item = std::tuple<double, size_t>;  // (height, index)
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
    for (int i = 0; i < rows; ++i)
        for (int j = 0; j < columns; ++j)
            if (i == 0 || j == 0 || i == rows - 1 || j == columns - 1) {
                const size_t c = size_t(i) * columns + j;
                closed[c] = 1;
                open.emplace(h[c], c);
            }
    constexpr int kDi[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
    constexpr int kDj[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
    while (!open.empty()) {
        const size_t c = std::get<1>(open.top());
        open.pop();
        const int ci = int(c / size_t(columns)), cj = int(c % size_t(columns));
        for (int k = 0; k < 8; ++k) {
            const int ni = ci + kDi[k], nj = cj + kDj[k];
            if (ni < 0 || nj < 0 || ni >= rows || nj >= columns) continue;
            const size_t nb = size_t(ni) * columns + nj;
            if (closed[nb]) continue;
            closed[nb] = 1;
            parent[nb] = int64_t(c);
            const double eps = (kDi[k] != 0 && kDj[k] != 0) ? eps_diagonal : eps_straight;
            if (h[nb] < h[c] + eps) {
                if (mode == TerrainCondition::Fill) {
                    h[nb] = h[c] + eps;
                } else {
                    // Lower the flood path from c back to the edge until it descends
                    // from nb by at least the slope at every step.
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
                }
            }
            open.emplace(h[nb], nb);
        }
    }
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

}  // namespace mr
