// Properties of the shallow-water core beyond SWASHES: the mass balance with sources, rain
// and open edges; the same result on any number of threads; dry cells left alone.
#include "shallow_water.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <vector>

namespace {

using mr::swe::EdgeKind;
using mr::swe::ShallowWater;
using mr::swe::ShallowWaterDef;

/// A tilted valley (V across, sloping along x) with a source at its head, rain and open edges.
ShallowWater valley(int n, double rain) {
    std::vector<double> z(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) z[static_cast<size_t>(j) * n + i] = 0.02 * std::abs(j - n / 2) + 0.01 * (n - i) + 0.3 * std::sin(0.3 * i) * std::cos(0.2 * j);
    ShallowWaterDef def;
    def.second_order = true;
    def.manning = 0.03;
    def.west = def.east = def.south = def.north = {EdgeKind::Open};
    ShallowWater w(n, n, 1.0, z, def);
    w.set_sources({{2, n / 2, 5.0}});
    w.set_rain(rain);
    return w;
}

}  // namespace

TEST(ShallowWater, MassBalanceHoldsWithASourceRainAndOpenEdges) {
    ShallowWater w = valley(64, 50e-3 / 3600.0);
    for (int f = 0; f < 600; ++f) w.advance(1.0 / 60.0);
    const auto b = w.balance();
    EXPECT_GT(b.inflow, 0.0);
    EXPECT_GT(b.rain, 0.0);
    EXPECT_GT(b.outflow, 0.0);
    // Round-off of doubles summed over ~10^3 steps of 4096 cells.
    EXPECT_LT(std::abs(b.error()), 1e-9 * (b.inflow + b.rain));
    EXPECT_EQ(w.stats().clipped, 0u);
}

TEST(ShallowWater, TheSameOnOneAndTwoThreads) {
    auto run = [](int threads) {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
        ShallowWater w = valley(96, 0.0);
        for (int f = 0; f < 120; ++f) w.advance(1.0 / 60.0);
        std::vector<double> s;
        for (int j = 0; j < w.ny(); ++j)
            for (int i = 0; i < w.nx(); ++i) s.insert(s.end(), {w.depth(i, j), w.discharge_x(i, j), w.discharge_y(i, j)});
        return s;
    };
    const std::vector<double> one = run(1), two = run(2), four = run(4);
    EXPECT_TRUE(one == two);
    EXPECT_TRUE(one == four);
}

TEST(ShallowWater, DryCellsAreSkipped) {
    // A source in a 256^2 dry map: after a second the updates stay near the wet cells.
    std::vector<double> z(256 * 256, 0.0);
    ShallowWaterDef def;
    ShallowWater w(256, 256, 1.0, z, def);
    w.set_sources({{128, 128, 1.0}});
    for (int f = 0; f < 60; ++f) w.advance(1.0 / 60.0);
    const double per_step = static_cast<double>(w.stats().cell_updates) / w.stats().substeps;
    EXPECT_GT(w.stats().substeps, 0u);
    EXPECT_LT(per_step, 0.1 * 256 * 256);
    EXPECT_NEAR(w.volume(), 1.0, 1e-9);
}
