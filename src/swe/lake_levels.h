// The steady spin-up's lake levels (swe.init = "steady", src/scene/swe_solver.cpp): a lake on
// a river's route settles to the level that passes its inflow over its outlet, but slowly,
// over A h / (1.5 Q) seconds for a lake of area A whose level stands h above its spill point
// passing Q (the weir law Q ~ h^1.5): 10^7 s for the 850-cell lake of the western USA crop
// (6 x 10^10 m^2, 0.3 m, 1,180 m^3/s), far beyond what the spin-up can afford to simulate.
// Its level then approaches the steady one geometrically from window to window: three levels
// L0, L1, L2 give the ratio r = (L2 - L1) / (L1 - L0) and the series' end, L2 + (L2 - L1)
// r / (1 - r) (Aitken's delta-squared), where the lake is moved.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

namespace mr::swe {

class ShallowWater;

/// A lake: its cells (row-major index j * nx + i) and the mean depth of its cells at its
/// spill level (the level never goes below it: the spill level passes nothing).
struct Lake {
    std::vector<int> cells;
    double spill_depth = 0.0;
};

class LakeLevels {
public:
    /// Ratios outside [kLeastRatio, kMostRatio] are not extrapolated: below, the lake settles
    /// within a few windows anyway; above, its level moves nearly linearly (a lake filling)
    /// and the series' end is not known (at kMostRatio a move is 49 times the last change).
    static constexpr double kLeastRatio = 0.2, kMostRatio = 0.98;
    /// A lake whose mean level moved less than this (metres) over a window is left alone
    /// (a lake at rest off the route, or one already steady).
    static constexpr double kLeastChange = 1e-7;

    explicit LakeLevels(std::vector<Lake> lakes) : lakes_(std::move(lakes)) {}
    /// Forgets the levels seen (the scheme changed).
    void restart() { seen_ = 0; }
    /// After a window of the spin-up: records each lake's mean depth; from the third window
    /// since the last move (or restart), moves each lake whose level changed the same way twice, the
    /// second time by r of the first (r in [kLeastRatio, kMostRatio]), to the end of that
    /// series (not below its spill level), every cell by the same height, its velocity
    /// kept. A lake whose volume changed by less than `least_volume` m^3 over the last
    /// window is left alone (it is as steady as the spin-up asks: a move would only stir it).
    /// Returns how many lakes moved (then it restarts).
    int after_window(ShallowWater& core, double least_volume);
    /// Lakes moved so far.
    uint64_t moves() const { return moves_; }

private:
    std::vector<Lake> lakes_;
    std::vector<double> levels_[3];
    int seen_ = 0;
    uint64_t moves_ = 0;
};

}  // namespace mr::swe
