#include "lake_levels.h"

#include "shallow_water.h"

#include <algorithm>
#include <cmath>

namespace mr::swe {

namespace {
double mean_depth(const ShallowWater& core, const Lake& lake) {
    double sum = 0.0;
    for (const int k : lake.cells) sum += core.depth(k % core.nx(), k / core.nx());
    return lake.cells.empty() ? 0.0 : sum / double(lake.cells.size());
}
}  // namespace

int LakeLevels::after_window(ShallowWater& core, double least_volume) {
    std::swap(levels_[0], levels_[1]);  // the latest three, oldest first
    std::swap(levels_[1], levels_[2]);
    levels_[2].resize(lakes_.size());
    for (size_t l = 0; l < lakes_.size(); ++l) levels_[2][l] = mean_depth(core, lakes_[l]);
    if (++seen_ < 3) return 0;
    int moved = 0;
    for (size_t l = 0; l < lakes_.size(); ++l) {
        const double d1 = levels_[1][l] - levels_[0][l], d2 = levels_[2][l] - levels_[1][l];
        const double area = double(lakes_[l].cells.size()) * core.dx() * core.dx();
        if (std::abs(d2) < kLeastChange || std::abs(d2) * area < least_volume || d1 * d2 <= 0.0) continue;
        const double r = d2 / d1;
        if (r < kLeastRatio || r > kMostRatio) continue;
        const double target = std::max(levels_[2][l] + d2 * r / (1.0 - r), lakes_[l].spill_depth);
        const double rise = target - levels_[2][l];
        if (rise == 0.0) continue;
        for (const int k : lakes_[l].cells) {
            const int i = k % core.nx(), j = k / core.nx();
            const double h = core.depth(i, j), to = std::max(h + rise, 0.0);
            const double keep = h > 0.0 ? to / h : 0.0;  // the same velocity
            core.set_state(i, j, to, core.discharge_x(i, j) * keep, core.discharge_y(i, j) * keep);
        }
        ++moved;
    }
    if (moved > 0) seen_ = 0;
    moves_ += uint64_t(moved);
    return moved;
}

}  // namespace mr::swe
