// Properties of the shallow-water core beyond SWASHES: the mass balance with sources, rain
// and open edges; the same result on any number of threads; dry cells left alone.
#include "shallow_water.h"
#include "swe_stage.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace {

using mr::swe::EdgeKind;
using mr::swe::FinishRow;
using mr::swe::ShallowWater;
using mr::swe::ShallowWaterDef;
using mr::swe::StageIn;
using mr::swe::StageKind;
using mr::swe::StageOut;

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

/// FNV-1a over the bits of every value a stage wrote, for each kind of stage, both orders,
/// open and walled edges, on a grid with dry cells, thin films, empty rows and ragged spans.
uint64_t stage_bits(bool& finite) {
    const int nx = 53, ny = 41;
    const size_t stride = nx + 2, cells = stride * (ny + 2);
    uint64_t seed = 12345, hash = 1469598103934665603ull;
    auto uniform = [&] {  // portable: no <random> distribution
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(seed >> 11) * 0x1.0p-53;
    };
    auto mix = [&](double x) {
        finite = finite && std::isfinite(x);
        uint64_t b;
        std::memcpy(&b, &x, sizeof b);
        for (int k = 0; k < 8; ++k) hash = (hash ^ ((b >> (8 * k)) & 255u)) * 1099511628211ull;
    };
    std::vector<double> z(cells), h(cells), hu(cells), hv(cells), rain(cells);
    for (size_t k = 0; k < cells; ++k) {
        z[k] = 0.5 * uniform();
        const double d = uniform();
        h[k] = d < 0.2 ? 0.0 : d < 0.3 ? 1e-4 * d : 1.5 * d;  // dry, thin films, wet
        hu[k] = h[k] * (2.0 * uniform() - 1.0);
        hv[k] = h[k] * (2.0 * uniform() - 1.0);
        rain[k] = 1e-3 * uniform();
    }
    std::vector<int> lo(ny), hi(ny);
    for (int j = 0; j < ny; ++j) {
        lo[j] = j % 7 == 3 ? 1 : static_cast<int>(uniform() * 10);  // row 3, 10, ...: empty
        hi[j] = j % 7 == 3 ? 0 : nx - 1 - static_cast<int>(uniform() * 10);
    }
    lo[0] = 0;  // the edges' spans reach the walls
    hi[ny - 1] = nx - 1;
    for (bool second : {false, true})
        for (bool walls : {false, true})
            for (StageKind kind : {StageKind::Euler, StageKind::HeunFirst, StageKind::HeunSecond}) {
                if (!second && kind != StageKind::Euler) continue;
                const bool heun = kind != StageKind::Euler;
                const StageIn in{.nx = nx, .ny = ny, .stride = stride, .z = z.data(), .h = h.data(), .hu = hu.data(),
                                 .hv = hv.data(), .lo = lo.data(), .hi = hi.data(), .r = 0.02, .weight = 0.05,
                                 .second = second, .friction = heun ? 0.01 : 0.0, .wall_west = walls,
                                 .wall_east = walls, .wall_south = walls, .wall_north = walls};
                std::vector<double> oh(h), ou(hu), ov(hv), row_out(ny + 1), row_in(ny + 1), row_rain(ny);
                std::vector<int> dirty_lo(ny, 0), dirty_hi(ny, nx - 1), wet_lo(ny), wet_hi(ny);
                std::vector<uint64_t> clip(ny, 0);
                const FinishRow finish{.rain_rate = rain.data(), .dt = 0.1};
                const StageOut out{.h = oh.data(), .hu = ou.data(), .hv = ov.data(), .dirty_lo = dirty_lo.data(),
                                   .dirty_hi = dirty_hi.data(), .row_out = row_out.data(), .row_in = row_in.data(),
                                   .row_clip = clip.data(), .finish = kind == StageKind::HeunSecond ? &finish : nullptr,
                                   .row_rain = row_rain.data(), .wet_lo = wet_lo.data(), .wet_hi = wet_hi.data()};
                run_stage(in, out, kind);
                for (const auto* v : {&oh, &ou, &ov, &row_out, &row_in, &row_rain})
                    for (double x : *v) mix(x);
                for (int j = 0; j < ny; ++j)
                    for (double x : {static_cast<double>(clip[j]), static_cast<double>(wet_lo[j]), static_cast<double>(wet_hi[j])}) mix(x);
            }
    return hash;
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

TEST(ShallowWater, SecondOrderBalancesRainOnKmCellsWithLargeSteps) {
    // Rain of 5 mm/h on hills of 8 km cells (slopes up to 6 %, Manning 0.03), advanced in
    // steps of 131.5 s (a frame at time_scale = the cell size), far under the CFL limit of
    // the slowed films: a Heun stage used to accelerate a film for the whole step with no
    // friction and drain more than its cell held; the clip created 0.7 % of the rain.
    const int n = 48;
    const double dx = 8000.0;
    std::vector<double> z(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) z[static_cast<size_t>(j) * n + i] = 800.0 * std::sin(0.5 * i) * std::cos(0.4 * j) + 30.0 * i;
    ShallowWaterDef def;
    def.second_order = true;
    def.manning = 0.03;
    def.dry_depth = 1e-3;
    def.west = def.east = def.south = def.north = {EdgeKind::Open};
    ShallowWater w(n, n, dx, z, def);
    w.set_rain(5e-3 / 3600.0);
    for (int f = 0; f < 300; ++f) w.advance(131.5);
    const auto b = w.balance();
    EXPECT_GT(b.outflow, 0.0);
    EXPECT_LT(std::abs(b.error()), 1e-12 * b.rain);
    EXPECT_EQ(w.stats().clipped, 0u);
}

TEST(ShallowWater, TheSameOnOneAndTwoThreads) {
    // Both orders, with a sink, a rain mask over half the map and an exchange between frames.
    auto run = [](int threads, bool second) {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, threads);
        ShallowWater w = valley(96, 0.0);
        ShallowWaterDef def = w.def();
        def.second_order = second;
        w.set_def(def);
        w.set_sources({{2, 48, 5.0}, {60, 48, -0.5}});
        std::vector<double> mask(96 * 96, 0.0);
        for (size_t k = 0; k < mask.size() / 2; ++k) mask[k] = 1e-4;
        w.set_rain_mask(mask);
        for (int f = 0; f < 120; ++f) {
            w.advance(1.0 / 60.0);
            w.exchange(30, 40, f % 2 ? 0.05 : -0.05, 0.01, 0.0);
        }
        std::vector<double> s;
        for (int j = 0; j < w.ny(); ++j)
            for (int i = 0; i < w.nx(); ++i) s.insert(s.end(), {w.depth(i, j), w.discharge_x(i, j), w.discharge_y(i, j)});
        const auto b = w.balance();
        s.insert(s.end(), {b.inflow, b.rain, b.outflow, b.sunk, b.exchanged, static_cast<double>(w.stats().cell_updates)});
        return s;
    };
    for (bool second : {false, true}) {
        const std::vector<double> one = run(1, second), two = run(2, second), four = run(4, second);
        EXPECT_TRUE(one == two) << "second order: " << second;
        EXPECT_TRUE(one == four) << "second order: " << second;
    }
}

TEST(ShallowWater, StagesHaveTheSameBitsOnEveryInstructionSet) {
    // The stage runs the AVX-512, AVX2 or baseline clone of its sweep, whichever the CPU
    // has: none may contract a product and a sum into an FMA or reorder a sum, so each gives
    // the bits the AVX2 clone gave when this was recorded (main at a712171, 2026-12-05; the
    // trench rule's first order since, recorded from the AVX-512 clone: the rule multiplies
    // the slopes by an exact 0 or 1 and compares a difference with 0.5 h, exact). A
    // change of the scheme or its round-off changes the hash: record the new one from a
    // build whose clones agree (run the test where each is picked, or build with one).
    bool finite = true;
    EXPECT_EQ(stage_bits(finite), 0xd113c8eb846c2de5ull);
    EXPECT_TRUE(finite);
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

namespace {

/// A flat walled basin of n x n cells (dx 2 m) holding `depth` metres of still water.
ShallowWater basin(int n, double depth) {
    std::vector<double> z(static_cast<size_t>(n) * n, 0.0);
    ShallowWaterDef def;
    def.second_order = true;
    ShallowWater w(n, n, 2.0, z, def);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) w.set_state(i, j, depth);
    w.balance_reset();
    return w;
}

double min_depth(const ShallowWater& w) {
    double m = 1e300;
    for (int j = 0; j < w.ny(); ++j)
        for (int i = 0; i < w.nx(); ++i) m = std::min(m, w.depth(i, j));
    return m;
}

}  // namespace

TEST(ShallowWater, SinksTakeAtMostWhatTheCellHolds) {
    // 10 cm over 32^2 cells of 4 m^2 is 409.6 m^3; a sink of 100 m^3/s for 2 s asks 200 m^3
    // but can take only what flows into its cell (a few m^3).
    ShallowWater w = basin(32, 0.1);
    w.set_sources({{16, 16, -100.0}, {3, 3, -0.01}});
    for (int f = 0; f < 120; ++f) w.advance(1.0 / 60.0);
    const auto b = w.balance();
    EXPECT_GT(b.sunk, 0.5);
    EXPECT_LT(b.sunk, 10.0);
    EXPECT_GE(min_depth(w), 0.0);
    EXPECT_EQ(w.stats().clipped, 0u);
    EXPECT_LT(std::abs(b.error()), 1e-12 * b.initial);
    // A sink in a dry map takes nothing.
    ShallowWater dry = basin(8, 0.0);
    dry.set_sources({{4, 4, -1.0}});
    dry.advance(1.0);
    EXPECT_EQ(dry.balance().sunk, 0.0);
    EXPECT_EQ(dry.volume(), 0.0);
}

TEST(ShallowWater, RainMaskRainsWhereItSays) {
    // A dry flat basin; rain only on a 4 x 4 block in one corner. Far cells stay dry, the
    // balance counts exactly the mask's volume.
    const int n = 64;
    ShallowWater w = basin(n, 0.0);
    std::vector<double> mask(static_cast<size_t>(n) * n, 0.0);
    for (int j = 2; j < 6; ++j)
        for (int i = 2; i < 6; ++i) mask[static_cast<size_t>(j) * n + i] = 1e-3;
    w.set_rain(5e-3);  // ignored while the mask is set
    w.set_rain_mask(mask);
    for (int f = 0; f < 60; ++f) w.advance(1.0 / 60.0);
    const auto b = w.balance();
    EXPECT_NEAR(b.rain, 16 * 1e-3 * 4.0 * 1.0, 1e-12);
    EXPECT_LT(std::abs(b.error()), 1e-12);
    EXPECT_GT(w.depth(3, 3), 0.0);
    EXPECT_EQ(w.depth(40, 40), 0.0);
    EXPECT_EQ(w.depth(2, 40), 0.0);
    // An empty mask: the uniform rate again, everywhere.
    w.set_rain_mask({});
    w.advance(1.0);
    EXPECT_NEAR(w.balance().rain - b.rain, 5e-3 * n * n * 4.0, 1e-9);
    EXPECT_GT(w.depth(40, 40), 0.0);
}

TEST(ShallowWater, ExchangeMovesVolumeAndMomentum) {
    const int n = 48;
    ShallowWater w = basin(n, 0.0);
    // 2 m^3 at 1.5 m/s along x into a dry cell of 4 m^2: 0.5 m deep, 0.75 m^2/s.
    EXPECT_DOUBLE_EQ(w.exchange(10, 20, 2.0, 3.0, 0.0), 2.0);
    EXPECT_DOUBLE_EQ(w.depth(10, 20), 0.5);
    EXPECT_DOUBLE_EQ(w.discharge_x(10, 20), 0.75);
    EXPECT_EQ(w.exchange(-1, 20, 2.0, 0.0, 0.0), 0.0);
    EXPECT_EQ(w.exchange(10, n, 2.0, 0.0, 0.0), 0.0);
    // The dry map's spans grow: the water spreads, mostly along +x, and the balance holds.
    for (int f = 0; f < 30; ++f) w.advance(1.0 / 60.0);
    EXPECT_GT(w.depth(11, 20), 0.0);
    EXPECT_GT(w.depth(10, 21), 0.0);
    EXPECT_GT(w.stats().cell_updates, 0u);
    double mx = 0.0;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) mx += w.discharge_x(i, j);
    EXPECT_GT(mx, 0.0);
    EXPECT_LT(std::abs(w.balance().error()), 1e-14);
    // Taking more than a cell holds takes what it holds; the velocity left unchanged when
    // the momentum taken is the volume times the cell's velocity.
    const double h = w.depth(11, 20), u = w.discharge_x(11, 20) / h;
    const double half = w.exchange(11, 20, -0.5 * h * 4.0, -0.5 * h * 4.0 * u, 0.0);
    EXPECT_NEAR(half, -0.5 * h * 4.0, 1e-15);
    EXPECT_NEAR(w.discharge_x(11, 20) / w.depth(11, 20), u, 1e-12);
    const double held = w.depth(12, 20) * 4.0;
    EXPECT_NEAR(w.exchange(12, 20, -100.0, 0.0, 0.0), -held, 1e-15);
    EXPECT_EQ(w.depth(12, 20), 0.0);
    EXPECT_EQ(w.discharge_x(12, 20), 0.0);
    const auto b = w.balance();
    EXPECT_NEAR(b.exchanged, 2.0 + half - held, 1e-15);
    EXPECT_LT(std::abs(b.error()), 1e-14);
    for (int f = 0; f < 30; ++f) w.advance(1.0 / 60.0);
    EXPECT_LT(std::abs(w.balance().error()), 1e-14);
    EXPECT_GE(min_depth(w), 0.0);
}

TEST(ShallowWater, ALineOfManySourcesFeedsItsSum) {
    // 300 sources of 0.01 m^3/s along a line (a line source) in a dry walled map.
    ShallowWater w = basin(400, 0.0);
    std::vector<mr::swe::PointSource> line;
    for (int i = 50; i < 350; ++i) line.push_back({i, 200, 0.01});
    w.set_sources(line);
    for (int f = 0; f < 60; ++f) w.advance(1.0 / 60.0);
    const auto b = w.balance();
    EXPECT_NEAR(b.inflow, 300 * 0.01 * 1.0, 1e-11);
    EXPECT_LT(std::abs(b.error()), 1e-11);
    // The spans follow the line: a few rows of 300-odd columns, not the 400^2 grid.
    const double per_step = static_cast<double>(w.stats().cell_updates) / w.stats().substeps;
    EXPECT_LT(per_step, 0.1 * 400 * 400);
}

TEST(ShallowWater, FrictionsCubeRootMatchesTheLibrary) {
    // The friction's vectorisable cube root against std::cbrt over 1e-12 m .. 1e4 m.
    double worst = 0.0;
    for (double x = 1e-12; x < 1e4; x *= 1.003) worst = std::max(worst, std::abs(mr::swe::cbrt_positive(x) / std::cbrt(x) - 1.0));
    EXPECT_LT(worst, 2e-15);
}

TEST(ShallowWater, WallsAreWatertightAtSecondOrder) {
    // A dam break sloshing in a walled basin over a bumpy bed: nothing crosses the walls at
    // either order (at second order a wall face sees the mirror of the inner cell's
    // reconstructed state, not the ghost's centre).
    const int n = 64;
    std::vector<double> z(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) z[static_cast<size_t>(j) * n + i] = 0.2 * std::sin(0.1 * i) * std::cos(0.13 * j);
    for (bool second : {false, true}) {
        ShallowWaterDef def;
        def.second_order = second;
        ShallowWater w(n, n, 1.0, z, def);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) w.set_state(i, j, std::max(0.0, (i < n / 2 ? 1.0 : 0.5) - w.bed(i, j)));
        w.balance_reset();
        for (int f = 0; f < 600; ++f) w.advance(1.0 / 60.0);
        const auto b = w.balance();
        EXPECT_EQ(b.outflow, 0.0) << "second order: " << second;
        EXPECT_EQ(b.inflow, 0.0) << "second order: " << second;
        EXPECT_LT(std::abs(b.stored - b.initial), 1e-12 * b.initial) << "second order: " << second;
    }
}

TEST(ShallowWater, EveryCellOutsideARowsWetSpanIsDryAndTheVolumeIsTheWholeGridsSum) {
    // A lake on the upper half of a tilted bumpy bed breaks and drains through the open
    // edges (rows wet, then dry again), with a sink, a cell set and one exchanged between
    // steps: after each step and each edit every cell outside its row's wet span holds no
    // water and no momentum, and volume() (which adds the spans only) and max_wave_speed()
    // equal the whole grid's, bit for bit.
    const int nx = 37, ny = 23;
    std::vector<double> z(static_cast<size_t>(nx) * ny);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) z[static_cast<size_t>(j) * nx + i] = 0.05 * i + 0.2 * std::sin(0.7 * i) * std::cos(0.5 * j);
    for (bool second : {false, true}) {
        ShallowWaterDef def;
        def.second_order = second;
        def.manning = 0.02;
        def.west = def.east = def.south = def.north = {EdgeKind::Open};
        ShallowWater w(nx, ny, 1.0, z, def);
        for (int j = 0; j < ny; ++j)
            for (int i = nx / 2; i < nx; ++i) w.set_state(i, j, std::max(0.0, 2.5 - w.bed(i, j)));
        w.set_sources({{30, 11, -2.0}});
        w.balance_reset();
        std::vector<uint8_t> was(static_cast<size_t>(nx) * ny, 0);
        size_t dried = 0;  // cells wet at one check, dry at a later one
        const auto check = [&](int f) {
            double v = 0.0, speed = 0.0;
            for (int j = 0; j < ny; ++j) {
                const auto [lo, hi] = w.wet_span(j);
                double row = 0.0;
                for (int i = 0; i < nx; ++i) {
                    const double h = w.depth(i, j);
                    row += h;
                    uint8_t& before = was[static_cast<size_t>(j) * nx + i];
                    dried += before && h == 0.0;
                    before = h > 0.0;
                    if (i < lo || i > hi) {
                        ASSERT_EQ(h, 0.0) << f << " " << i << " " << j;
                        ASSERT_EQ(w.discharge_x(i, j), 0.0) << f << " " << i << " " << j;
                        ASSERT_EQ(w.discharge_y(i, j), 0.0) << f << " " << i << " " << j;
                    }
                    if (h > def.dry_depth) {
                        const double c = std::sqrt(def.gravity * h);
                        speed = std::max({speed, std::abs(w.discharge_x(i, j) / h) + c, std::abs(w.discharge_y(i, j) / h) + c});
                    }
                }
                v += row;
            }
            ASSERT_EQ(w.volume(), v * w.dx() * w.dx()) << f;
            ASSERT_EQ(w.max_wave_speed(), speed) << f;
        };
        for (int f = 0; f < 400; ++f) {
            w.advance(0.1);
            check(f);
            if (f == 100) w.set_state(3, 4, 0.7, 0.1, -0.2);  // water where there was none
            if (f == 150) w.set_state(3, 4, 0.0);             // and none again
            if (f == 200) w.exchange(5, 20, 0.3, 0.1, 0.0);
            check(f);
        }
        EXPECT_GE(dried, 2u) << second;  // the sink emptied its cell, the cell set dry (films elsewhere stay > 0)
    }
}

namespace {

/// A channel 3 cells wide between walls, flat bed, a lake h0 deep against an outfall at the
/// east end; the volume that leaves from t0 to t1 seconds per metre of edge and second.
double outfall_rate(bool second, double h0, double t0, double t1) {
    const int nx = 400, ny = 3;
    const std::vector<double> z(static_cast<size_t>(nx) * ny, 0.0);
    ShallowWaterDef def;
    def.second_order = second;
    def.east = {EdgeKind::Outfall};
    ShallowWater w(nx, ny, 1.0, z, def);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) w.set_state(i, j, h0);
    w.balance_reset();
    w.advance(t0);
    const double out0 = w.balance().outflow;
    w.advance(t1 - t0);
    const auto b = w.balance();
    EXPECT_EQ(b.inflow, 0.0);
    EXPECT_LT(std::abs(b.error()), 1e-12 * b.initial);
    return (b.outflow - out0) / ((t1 - t0) * ny);
}

}  // namespace

TEST(ShallowWater, OutfallDrainsALakeAtItsCriticalDepth) {
    // A lake at rest against a free overfall: the rarefaction leaves the edge at the critical
    // state h = 4/9 h0, u = sqrt(g h) (Ritter's dam break at x = 0), q = (8/27) sqrt(g) h0^1.5,
    // until the wave reflected from the far wall (400 m at 3.1 m/s) comes back.
    const double g = 9.81, h0 = 1.0, q = 8.0 / 27.0 * std::sqrt(g) * std::pow(h0, 1.5);
    for (bool second : {false, true}) {
        const double measured = outfall_rate(second, h0, 20.0, 100.0);
        EXPECT_NEAR(measured / q, 1.0, 0.01) << "second order: " << second << ", q " << measured << " (critical " << q << ")";
    }
}

TEST(ShallowWater, OutfallLeavesALakeBehindARimAtRest) {
    // Well balanced away from the edge: a lake over bumps held by a rim two cells before an
    // outfall stays at rest to round-off, and nothing leaves (the cells beyond the rim dry).
    const int n = 48;
    std::vector<double> z(static_cast<size_t>(n) * n);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i)
            z[static_cast<size_t>(j) * n + i] = i == n - 3 ? 2.0 : 0.3 * std::sin(0.4 * i) * std::cos(0.3 * j) - 0.01 * i;
    for (bool second : {false, true}) {
        ShallowWaterDef def;
        def.second_order = second;
        def.west = def.south = def.north = {EdgeKind::Wall};
        def.east = {EdgeKind::Outfall};
        ShallowWater w(n, n, 1.0, z, def);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n - 3; ++i) w.set_state(i, j, 1.0 - w.bed(i, j));
        w.balance_reset();
        for (int f = 0; f < 120; ++f) w.advance(1.0 / 30.0);
        double fastest = 0.0;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) fastest = std::max({fastest, std::abs(w.discharge_x(i, j)), std::abs(w.discharge_y(i, j))});
        EXPECT_LT(fastest, 1e-12) << "second order: " << second;
        EXPECT_EQ(w.balance().outflow, 0.0) << "second order: " << second;
    }
}

TEST(ShallowWater, MassBalanceHoldsWithOutfallEdges) {
    ShallowWater w = valley(64, 50e-3 / 3600.0);
    ShallowWaterDef def = w.def();
    def.west = def.east = def.south = def.north = {EdgeKind::Outfall};
    w.set_def(def);
    for (int f = 0; f < 600; ++f) w.advance(1.0 / 60.0);
    const auto b = w.balance();
    EXPECT_GT(b.outflow, 0.0);
    EXPECT_NEAR(b.inflow, 5.0 * w.time(), 1e-9 * b.inflow);  // the source only: an outfall lets nothing in
    EXPECT_LT(std::abs(b.error()), 1e-9 * (b.inflow + b.rain));
    EXPECT_EQ(w.stats().clipped, 0u);
}

TEST(ShallowWater, APitBehindACrestDrainsOverItWithoutDrivingItsWholeColumn) {
    // western_usa's outlet at 8.3 km cells, across x: a dry bank, a pit 103 m deep whose
    // level stands 5 cm over the crest beside it (a 1 cm sheet), a lake below the crest, dry
    // land to the outfall. The pit spills over the crest as a weir with a 5 cm head, about
    // 1.7 h^1.5 = 0.02 m^2/s. The second order's limiter took the surface's step down to
    // the crest's sheet as a tilt across the whole pit (its other neighbour, the dry bank,
    // pins nothing), and the centred bed-slope term drove the 103 m column with it: 81 m^2/s
    // within 20,000 s, the pit pumped above its lake and then emptied over the crest in bursts.
    const int nx = 6, ny = 3;
    const double bed[nx] = {5210.0, 4981.0, 5084.0, 4943.0, 4959.0, 4900.0};
    const double level[nx] = {0.0, 5084.05, 5084.01, 4959.0, 0.0, 0.0};
    std::vector<double> z(static_cast<size_t>(nx) * ny);
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) z[static_cast<size_t>(j) * nx + i] = bed[i];
    for (bool second : {false, true}) {
        ShallowWaterDef def;
        def.second_order = second;
        def.manning = 0.03;
        def.west = def.south = def.north = {EdgeKind::Wall};
        def.east = {EdgeKind::Outfall};
        ShallowWater w(nx, ny, 8309.0, z, def);
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i) w.set_state(i, j, std::max(level[i] - bed[i], 0.0));
        w.balance_reset();
        double fastest = 0.0;
        for (int k = 0; k < 20; ++k) {
            w.advance(1000.0);
            for (int j = 0; j < ny; ++j) fastest = std::max(fastest, std::abs(w.discharge_x(1, j)));
        }
        EXPECT_LT(fastest, 0.1) << "second order: " << second;
        EXPECT_LT(std::abs(w.balance().error()), 1e-12 * w.balance().initial);
    }
}
