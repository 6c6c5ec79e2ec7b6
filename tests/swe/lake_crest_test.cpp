// The steady init's starting head over a lake's spill level (src/swe/lake_crest.h): the crest
// cells the water leaves by (not the far shore), the head of a crest several cells wide, a
// friction-controlled outlet on a mild slope, and both against the level the shallow-water
// core settles to under the same discharge.
#include "lake_crest.h"
#include "shallow_water.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

namespace mr::swe {
namespace {

constexpr double kSpill = 1.0, kWall = 3.0, kInflow = 0.5, kManning = 0.03;
constexpr int kNy = 31;
/// Ritter's dam-break flux per metre over a crest under H: (8/27) sqrt(g) H^(3/2).
constexpr double kRitter = 8.0 / 27.0 * 3.1320919526731650;  // sqrt(9.81)

/// A 20 x 25 lake of 1 m cells (bed 0, spill level 1 m) in walls 3 m high; on its east side a
/// crest `width` cells wide at the spill level, then a channel as wide sloping down at
/// `slope` to the map's east edge. The far (west) shore stands 2 cm over the spill level:
/// under the head it is wet, but no water leaves over it.
struct Basin {
    int nx = 90;
    std::vector<double> bed, level;
    std::vector<int> lake;
    int first = 0, width = 0;  // the crest's rows

    Basin(int crest_width, double slope, int columns = 90)
        : nx(columns), bed(size_t(columns) * kNy, kWall), first(15 - crest_width / 2), width(crest_width) {
        for (int j = 3; j <= 27; ++j)
            for (int i = 3; i <= 22; ++i) {
                bed[at(i, j)] = 0.0;
                lake.push_back(j * nx + i);
            }
        for (int j = 3; j <= 27; ++j) bed[at(2, j)] = kSpill + 0.02;  // the far shore
        for (int j = first; j < first + width; ++j)
            for (int i = 23; i < nx; ++i) bed[at(i, j)] = kSpill - slope * (i - 23);
        level = bed;  // every cell but the lake's drains over its own bed
        for (const int k : lake) level[size_t(k)] = kSpill;
    }
    size_t at(int i, int j) const { return size_t(j) * nx + i; }
    CrestGrid grid(double manning) const { return {.nx = nx, .ny = kNy, .dx = 1.0, .bed = bed, .level = level, .manning = manning}; }

    /// The lake's mean level after `seconds` of kInflow from its west side, from rest at the
    /// spill level (second order, Manning's n, water leaving through the east edge: `edge`).
    double settled_level(double manning, EdgeKind edge, double seconds, double* out_over_in) const {
        ShallowWaterDef def;
        def.second_order = true;
        def.manning = manning;
        def.east = {edge};
        ShallowWater w(nx, kNy, 1.0, bed, def);
        for (const int k : lake) w.set_state(k % nx, k / nx, kSpill - bed[size_t(k)]);
        w.set_sources({{4, 15, kInflow}});
        w.advance(seconds - 100.0);
        w.balance_reset();
        w.advance(100.0);
        *out_over_in = w.balance().outflow / w.balance().inflow;
        double sum = 0.0;
        for (const int k : lake) sum += w.bed(k % nx, k / nx) + w.depth(k % nx, k / nx);
        return sum / double(lake.size());
    }
};

TEST(LakeCrest, TheCrestIsTheCellsTheWaterLeavesByNotTheShore) {
    Basin b(5, 0.1);
    for (const int j : {b.first - 1, b.first + b.width})  // the rim beside the crest, as low as the far shore
        b.bed[b.at(23, j)] = b.level[b.at(23, j)] = kSpill + 0.02;
    const std::vector<Crest> crests = find_crests(b.grid(kManning), b.lake, kSpill, 1.0);
    ASSERT_EQ(crests.size(), 5u);  // the crest's cells, not the 25 + 2 shore cells under the head
    for (const Crest& c : crests) {
        EXPECT_EQ(c.cell % b.nx, 23);
        EXPECT_GE(c.cell / b.nx, b.first);
        EXPECT_LT(c.cell / b.nx, b.first + b.width);
        EXPECT_NEAR(c.slope, 0.1, 1e-12);  // the drop to the next cell of the channel
    }
    // With the shore counted (29 cells over 2 cm below the head) the head would be lower.
    const double h = crest_head(b.grid(0.0), b.lake, kSpill, kInflow);
    EXPECT_NEAR(h, std::pow(kInflow / (kRitter * 5.0), 2.0 / 3.0), 1e-8);
}

TEST(LakeCrest, AFlatCrestSeveralCellsLongLeadsOutAndAFlatShoreDoesNot) {
    Basin b(3, 0.1);
    for (int j = b.first; j < b.first + b.width; ++j)  // the crest 4 cells long, then the chute
        for (int i = 23; i < b.nx; ++i) b.bed[b.at(i, j)] = b.level[b.at(i, j)] = i < 27 ? kSpill : kSpill - 0.1 * (i - 26);
    for (int j = 3; j <= 27; ++j) b.bed[b.at(2, j)] = b.level[b.at(2, j)] = kSpill;  // a flat shore at the spill level
    const std::vector<Crest> crests = find_crests(b.grid(kManning), b.lake, kSpill, 1.0);
    ASSERT_EQ(crests.size(), 3u);  // the brink of the flat, not the flat shore
    for (const Crest& c : crests) {
        EXPECT_EQ(c.cell % b.nx, 26);
        EXPECT_NEAR(c.slope, 0.1, 1e-12);
    }
    CrestGrid near = b.grid(kManning);  // the brink lies 4 cells from the lake
    near.most_steps = 3;
    EXPECT_TRUE(find_crests(near, b.lake, kSpill, 1.0).empty());
}

TEST(LakeCrest, NoCrestIsNaNAndNoDischargeNoHead) {
    Basin b(5, 0.1);
    for (int j = b.first; j < b.first + b.width; ++j)  // sealed: the crest and the channel as high as the walls
        for (int i = 23; i < b.nx; ++i) b.bed[b.at(i, j)] = b.level[b.at(i, j)] = kWall;
    EXPECT_TRUE(find_crests(b.grid(kManning), b.lake, kSpill, 1.0).empty());
    EXPECT_TRUE(std::isnan(crest_head(b.grid(kManning), b.lake, kSpill, kInflow)));
    EXPECT_EQ(crest_head(b.grid(kManning), b.lake, kSpill, 0.0), 0.0);
}

TEST(LakeCrest, ACrestPassesRittersFluxOrLessWhereFrictionSlowsTheFlowAfterIt) {
    EXPECT_NEAR(crest_flow(0.2, HUGE_VAL, kManning, 9.81), kRitter * std::pow(0.2, 1.5), 1e-12);
    EXPECT_NEAR(crest_flow(0.2, 1e-3, 0.0, 9.81), kRitter * std::pow(0.2, 1.5), 1e-12);  // no friction
    EXPECT_NEAR(crest_flow(0.2, 0.1, kManning, 9.81), kRitter * std::pow(0.2, 1.5), 1e-12);  // steep: supercritical
    EXPECT_EQ(crest_flow(-0.1, 0.1, kManning, 9.81), 0.0);
    // Mild: Manning's flow h deep with sqrt(g H) = sqrt(g h) + u / 2.
    const double q = crest_flow(0.2, 1e-3, kManning, 9.81);
    EXPECT_LT(q, kRitter * std::pow(0.2, 1.5));
    double h = 0.01;  // the depth that passes q in uniform flow, by fixed point
    for (int it = 0; it < 200; ++it) h = std::pow(q * kManning / std::sqrt(1e-3), 0.6);
    const double u = q / h;
    EXPECT_NEAR(std::sqrt(9.81 * 0.2), std::sqrt(9.81 * h) + 0.5 * u, 1e-9);
}

// The lake settles where the estimate put it, from rest at its spill level: a crest 5 cells
// wide over a steep chute (Ritter's flux: the ideal broad crest's head, 1.705 H^1.5, is 0.67 of
// the settled one; one cell's ideal head 1.43 of it), and the same crest before a channel
// 500 cells long sloping 1e-3 to a free overfall (friction controls: Manning's normal depth
// alone is 0.84 of the settled head, one cell's ideal weir head 1.52 of it). The tolerance:
// 3 % of the head over the chute (it settles 0.6 % under), 10 % on the mild slope (7.7 %
// over: the lake cells next to the crest move at 0.12 m/s toward it, which the estimate's
// lake at rest leaves out; with sqrt(g H) + u_lake / 2 on the left it is 0.3 %).
TEST(LakeCrest, TheLakeSettlesAtTheHeadOfItsCrestFreeFallOrFriction) {
    struct Case {
        double slope;
        int columns;
        EdgeKind edge;
        double seconds;  // 10 times the lake's settling time A h / (1.5 Q), and the channel's filling
        double tolerance;
    };
    for (const Case& c : {Case{0.1, 60, EdgeKind::Open, 1500.0, 0.03}, Case{1e-3, 530, EdgeKind::Outfall, 5000.0, 0.1}}) {
        SCOPED_TRACE(c.slope);
        const Basin b(5, c.slope, c.columns);
        const double head = crest_head(b.grid(kManning), b.lake, kSpill, kInflow);
        const double ideal = std::pow(kInflow / (1.705 * 5.0), 2.0 / 3.0), one_cell = std::pow(kInflow / 1.705, 2.0 / 3.0);
        const double normal = std::pow(kInflow / 5.0 * kManning / std::sqrt(c.slope), 0.6);
        double out_over_in = 0.0;
        const double settled = b.settled_level(kManning, c.edge, c.seconds, &out_over_in) - kSpill;
        std::printf("slope %g: head %.4f (ideal weir %.4f, normal depth %.4f, one cell %.4f), settled %.4f, out/in %.5f\n",
                    c.slope, head, ideal, normal, one_cell, settled, out_over_in);
        EXPECT_NEAR(out_over_in, 1.0, 2e-3);  // steady (the last 100 s)
        EXPECT_NEAR(settled, head, c.tolerance * head);
        EXPECT_GT(std::abs(std::max(ideal, normal) - settled), 0.12 * settled);  // the ideal weir or normal depth: off
        EXPECT_GT(std::abs(one_cell - settled), 0.4 * settled);                   // the old one-cell estimate: far off
    }
}

/// A lake (bed 0, spill 1 m) with two outlets at its spill level: a crest 3 cells wide east
/// and one cell wide west, each down a channel into its own lower lake (bed -3 m, spill -2 m)
/// that drains off the map's edge; a side pit beside the channels that no crest feeds.
TEST(LakeCrest, TheRouteSplitsALakesOutflowBetweenItsCrestsIntoTheLakesBelow) {
    constexpr int nx = 41, ny = 11;
    std::vector<double> bed(size_t(nx) * ny, 5.0);
    std::vector<int> from(size_t(nx) * ny, -1);
    std::vector<std::vector<int>> lakes(4);  // upper, east, west, side
    const auto at = [&](int i, int j) { return j * nx + i; };
    for (int j = 3; j <= 5; ++j) {
        for (int i = 16; i <= 24; ++i) lakes[0].push_back(at(i, j)), bed[size_t(at(i, j))] = 0.0;
        bed[size_t(at(25, j))] = 1.0;  // the east crest
        for (int i = 26; i <= 28; ++i) bed[size_t(at(i, j))] = 1.0 - 0.1 * (i - 25);
        for (int i = 29; i <= 33; ++i) lakes[1].push_back(at(i, j)), bed[size_t(at(i, j))] = -3.0;
    }
    bed[size_t(at(15, 4))] = 1.0;  // the west crest
    for (int i = 12; i <= 14; ++i) bed[size_t(at(i, 4))] = 1.0 - 0.1 * (15 - i);
    for (int j = 3; j <= 5; ++j)
        for (int i = 5; i <= 11; ++i) lakes[2].push_back(at(i, j)), bed[size_t(at(i, j))] = -3.0;
    for (int i = 34; i < nx; ++i) bed[size_t(at(i, 4))] = -2.0 - 0.01 * (i - 33);  // out east
    for (int i = 0; i <= 4; ++i) bed[size_t(at(i, 4))] = -2.0 - 0.01 * (5 - i);    // out west
    for (int i = 16; i <= 24; ++i) lakes[3].push_back(at(i, 8)), bed[size_t(at(i, 8))] = -1.0;  // the side pit
    std::vector<double> level = bed;
    for (const int k : lakes[0]) level[size_t(k)] = 1.0;
    for (const int l : {1, 2})
        for (const int k : lakes[size_t(l)]) level[size_t(k)] = -2.0;
    for (const int k : lakes[3]) level[size_t(k)] = 5.0;  // walled in: its spill is the wall's
    // The flood's paths: along row 4 towards each edge from the middle, rows 3 and 5 into row 4.
    for (int j = 3; j <= 5; ++j)
        for (int i = 1; i < nx - 1; ++i) from[size_t(at(i, j))] = j != 4 ? at(i, 4) : i >= 20 ? at(i + 1, 4) : at(i - 1, 4);
    for (int i = 16; i <= 24; ++i) from[size_t(at(i, 8))] = at(i, 9);
    const CrestGrid grid{.nx = nx, .ny = ny, .dx = 1.0, .bed = bed, .level = level, .manning = kManning};
    const std::vector<int> starts{at(20, 1)};
    from[size_t(at(20, 1))] = at(20, 2);
    from[size_t(at(20, 2))] = at(20, 3);
    const std::vector<LakeFlow> flow = route_lakes(grid, lakes, from, starts, kInflow);
    ASSERT_EQ(flow.size(), 4u);
    EXPECT_DOUBLE_EQ(flow[0].inflow, kInflow);
    EXPECT_NEAR(flow[0].head, crest_head(grid, lakes[0], 1.0, kInflow), 1e-12);
    EXPECT_NEAR(flow[1].inflow + flow[2].inflow, kInflow, 1e-9);  // nothing lost between the lakes
    EXPECT_NEAR(flow[1].inflow / flow[2].inflow, 3.0, 1e-6);     // three crest cells east, one west
    EXPECT_GT(flow[1].head, flow[2].head);
    EXPECT_NEAR(flow[1].head, crest_head(grid, lakes[1], -2.0, flow[1].inflow), 1e-12);
    EXPECT_EQ(flow[3].inflow, 0.0);  // no crest feeds the side pit
    EXPECT_EQ(flow[3].head, 0.0);
}

}  // namespace
}  // namespace mr::swe
