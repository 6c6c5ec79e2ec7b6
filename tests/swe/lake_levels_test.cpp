// The steady spin-up's lake extrapolation (src/swe/lake_levels.h): a lake whose level
// approaches its steady one geometrically from window to window is moved to where the series
// ends; a lake filling linearly, one that turned, or one already as steady as asked is left.
#include "lake_levels.h"
#include "shallow_water.h"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

namespace mr::swe {
namespace {

// A 6 x 4 grid of 10 m cells, a lake of the 2 x 2 cells in the middle over a bed 1 m lower
// there (its spill depth 1 m), the rest dry.
struct Basin {
    std::vector<double> bed = std::vector<double>(24, 1.0);
    std::unique_ptr<ShallowWater> core;
    Lake lake{{1 * 6 + 2, 1 * 6 + 3, 2 * 6 + 2, 2 * 6 + 3}, 1.0};
    Basin() {
        for (const int k : lake.cells) bed[size_t(k)] = 0.0;
        core = std::make_unique<ShallowWater>(6, 4, 10.0, bed, ShallowWaterDef{});
    }
    void level(double depth) {  // the lake's cells at this depth, each moving at 0.5 m/s
        for (const int k : lake.cells) core->set_state(k % 6, k / 6, depth, 0.5 * depth, 0.0);
    }
};

TEST(LakeLevels, AGeometricApproachIsMovedToItsEnd) {
    Basin b;
    LakeLevels lakes({b.lake});
    // 1.5 - 0.2 r^n with r = 0.9: the end is 1.5 m.
    for (int n = 0; n < 3; ++n) {
        b.level(1.5 - 0.2 * std::pow(0.9, n));
        EXPECT_EQ(lakes.after_window(*b.core, 0.0), n == 2 ? 1 : 0) << n;
    }
    for (const int k : b.lake.cells) {
        EXPECT_NEAR(b.core->depth(k % 6, k / 6), 1.5, 1e-12);
        EXPECT_NEAR(b.core->discharge_x(k % 6, k / 6) / b.core->depth(k % 6, k / 6), 0.5, 1e-12);  // velocity kept
    }
    EXPECT_EQ(b.core->depth(0, 0), 0.0);  // outside the lake: untouched
    EXPECT_EQ(lakes.moves(), 1u);
    // A draining lake ends at its spill level at the lowest: 1.2 + 0.3 r^n with r = 0.5 would
    // end at 1.2 m; 0.9 + ... below the spill depth 1 m stops at 1 m.
    for (int n = 0; n < 3; ++n) {
        b.level(0.9 + 0.3 * std::pow(0.5, n));
        lakes.after_window(*b.core, 0.0);
    }
    EXPECT_NEAR(b.core->depth(2, 1), 1.0, 1e-12);
}

TEST(LakeLevels, ALinearRiseATurnAndASmallChangeAreLeftAlone) {
    const auto moved = [](double l0, double l1, double l2, double least_volume) {
        Basin b;
        LakeLevels lakes({b.lake});
        int m = 0;
        for (const double l : {l0, l1, l2}) {
            b.level(l);
            m += lakes.after_window(*b.core, least_volume);
        }
        return m;
    };
    EXPECT_EQ(moved(1.1, 1.2, 1.3, 0.0), 0);    // filling linearly: r = 1
    EXPECT_EQ(moved(1.1, 1.3, 1.2, 0.0), 0);    // turned
    EXPECT_EQ(moved(1.1, 1.2, 1.201, 0.0), 0);  // r = 0.01: settling fast on its own
    // 400 m^2 of lake moving 0.09 m in the last window: 36 m^3.
    EXPECT_EQ(moved(1.1, 1.2, 1.29, 35.0), 1);
    EXPECT_EQ(moved(1.1, 1.2, 1.29, 37.0), 0);
}

}  // namespace
}  // namespace mr::swe
