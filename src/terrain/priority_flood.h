// The priority flood over a grid of heights, private to mr_terrain: the one flood that
// both the drainage network (drainage.cpp: depression filling before D8) and the
// drainage conditioning (condition.cpp: fill or breach) run.
//
// R. Barnes, C. Lehman, D. Mulla, "Priority-Flood: An optimal depression-filling and
// watershed-labeling algorithm for digital elevation models", Computers & Geosciences
// 62, 2014.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <queue>
#include <tuple>
#include <vector>

namespace mr {

/// The 8 neighbours of a grid cell (row offset, column offset), in the order every
/// drainage pass visits them: ties (the steepest of equal drops, the first to reach a
/// cell) go to the first.
inline constexpr int kNeighbourDi[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
inline constexpr int kNeighbourDj[8] = {-1, 0, 1, -1, 1, -1, 0, 1};

/// f(n, diagonal) for the 8 neighbours n of cell c of a rows x columns grid (row-major)
/// that lie in the grid, in kNeighbourDi/kNeighbourDj order.
template <class F>
void for_neighbours(int rows, int columns, size_t c, F&& f) {
    const int i = int(c / size_t(columns)), j = int(c % size_t(columns));
    for (int k = 0; k < 8; ++k) {
        const int a = i + kNeighbourDi[k], b = j + kNeighbourDj[k];
        if (a < 0 || b < 0 || a >= rows || b >= columns) continue;
        f(size_t(a) * size_t(columns) + size_t(b), kNeighbourDi[k] != 0 && kNeighbourDj[k] != 0);
    }
}

/// Visits every cell of a rows x columns grid of heights (row-major) once, from the
/// border inwards in order of height: the border cells are queued at their heights; then
/// the queued cell of the lowest (height, index) (ties by index: deterministic) reaches
/// each of its neighbours not reached before, in for_neighbours order:
/// reach(from, cell, diagonal) sets height[cell] from height[from] (it may change other
/// cells too: a breach lowers the way back to the border), and the cell is queued at its
/// new height. A cell's queued height is not updated when a later reach lowers it.
/// O(n log n).
template <class Reach>
void priority_flood(std::vector<double>& height, int rows, int columns, Reach&& reach) {
    const size_t n = size_t(rows) * size_t(columns);
    std::vector<uint8_t> closed(n, 0);
    using Item = std::tuple<double, size_t>;  // (height, index)
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
    for (int i = 0; i < rows; ++i)
        for (int j = 0; j < columns; ++j)
            if (i == 0 || j == 0 || i == rows - 1 || j == columns - 1) {
                const size_t c = size_t(i) * size_t(columns) + size_t(j);
                closed[c] = 1;
                open.emplace(height[c], c);
            }
    while (!open.empty()) {
        const size_t c = std::get<1>(open.top());
        open.pop();
        for_neighbours(rows, columns, c, [&](size_t m, bool diagonal) {
            if (closed[m]) return;
            closed[m] = 1;
            reach(c, m, diagonal);
            open.emplace(height[m], m);
        });
    }
}

}  // namespace mr
