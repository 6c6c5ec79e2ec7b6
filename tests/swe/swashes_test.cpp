// The shallow-water core against SWASHES' analytic solutions (swashes.h): each case at two or
// three resolutions, its error norms and observed orders printed as the rows of the table in
// docs/shallow-water.md (`build/default/tests/swe_tests --gtest_filter='Swashes.*'`), and the
// orders asserted within bounds set from what a first/second-order scheme can reach on the
// case (discontinuities and dry fronts bound every scheme to about 1 in L1).
#include "shallow_water.h"
#include "swashes.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>
#include <vector>

namespace {

using mr::swe::Edge;
using mr::swe::EdgeKind;
using mr::swe::ShallowWater;
using mr::swe::ShallowWaterDef;

/// A 1D case on a strip one cell wide (walls on its sides), cells centred at (i + 1/2) dx.
ShallowWater strip(int nx, double length, const std::function<double(double)>& bed,
                   const std::function<swashes::Sample(double)>& init, Edge west, Edge east, bool second_order) {
    const double dx = length / nx;
    std::vector<double> z(nx);
    for (int i = 0; i < nx; ++i) z[i] = bed((i + 0.5) * dx);
    ShallowWaterDef def;
    def.second_order = second_order;
    def.west = west;
    def.east = east;
    ShallowWater w(nx, 1, dx, z, def);
    for (int i = 0; i < nx; ++i) {
        const swashes::Sample s = init((i + 0.5) * dx);
        w.set_state(i, 0, s.h, s.h * s.u);
    }
    w.balance_reset();
    return w;
}

struct Row {
    int n = 0;
    swashes::Norms h, q;
};

double order(double coarse, double fine) { return std::log2(coarse / fine); }

/// Prints the case's rows (the docs' table) and returns the L1 orders of depth between
/// successive resolutions.
std::vector<double> report(const std::string& name, const std::vector<Row>& rows, bool with_q) {
    std::vector<double> orders;
    for (size_t k = 0; k < rows.size(); ++k) {
        const Row& r = rows[k];
        const std::string oh = k ? fmt::format("{:.2f}", order(rows[k - 1].h.l1, r.h.l1)) : "-";
        const std::string oq = k && with_q ? fmt::format("{:.2f}", order(rows[k - 1].q.l1, r.q.l1)) : "-";
        const std::string q = with_q ? fmt::format("{:.3e} | {:.3e} | {:.3e}", r.q.l1, r.q.l2, r.q.linf) : "- | - | -";
        fmt::print("| {} | {} | {:.3e} | {:.3e} | {:.3e} | {} | {} | {} |\n", name, r.n, r.h.l1, r.h.l2, r.h.linf, oh, q, oq);
        if (k) orders.push_back(order(rows[k - 1].h.l1, r.h.l1));
    }
    return orders;
}

/// A 1D case's errors against the exact depth and discharge at the cell centres.
Row errors_1d(const ShallowWater& w, const std::function<swashes::Sample(double)>& exact) {
    std::vector<double> eh(w.nx()), eq(w.nx());
    for (int i = 0; i < w.nx(); ++i) {
        const swashes::Sample s = exact((i + 0.5) * w.dx());
        eh[i] = w.depth(i, 0) - s.h;
        eq[i] = w.discharge_x(i, 0) - s.h * s.u;
    }
    return {w.nx(), swashes::norms(eh, w.dx()), swashes::norms(eq, w.dx())};
}

void lake_at_rest(double level, const char* name) {
    for (bool second : {false, true})
        for (int n : {100, 200}) {
            auto init = [&](double x) { return swashes::Sample{std::max(level - swashes::bump(x), 0.0), 0.0}; };
            ShallowWater w = strip(n, 25.0, swashes::bump, init, {}, {}, second);
            w.advance(20.0);
            double dev = 0.0, q = 0.0;
            std::vector<double> eh(n);
            for (int i = 0; i < n; ++i) {
                eh[i] = w.depth(i, 0) - init((i + 0.5) * w.dx()).h;
                if (w.depth(i, 0) > 0.0) dev = std::max(dev, std::abs(w.depth(i, 0) + w.bed(i, 0) - level));
                q = std::max(q, std::abs(w.discharge_x(i, 0)));
            }
            const swashes::Norms nh = swashes::norms(eh, w.dx());
            fmt::print("| {} ({} order, 20 s) | {} | {:.1e} | {:.1e} | {:.1e} | - | - | - | {:.1e} | - |\n", name,
                       second ? "2nd" : "1st", n, nh.l1, nh.l2, nh.linf, q);
            // Round-off: a few ulps of the 2 m level per step, over hundreds of steps.
            EXPECT_LT(dev, 1e-12) << name << " n=" << n;
            EXPECT_LT(q, 1e-12) << name << " n=" << n;
            EXPECT_NEAR(w.balance().error(), 0.0, 1e-12 * w.balance().initial);
            EXPECT_EQ(w.stats().clipped, 0u);
        }
}

}  // namespace

TEST(Swashes, LakeAtRestImmersedBumpStaysAtRestToRoundOff) { lake_at_rest(0.5, "lake at rest, immersed bump"); }

TEST(Swashes, LakeAtRestEmergedBumpStaysAtRestToRoundOff) { lake_at_rest(0.1, "lake at rest, emerged bump"); }

TEST(Swashes, StokerRootSatisfiesRankineHugoniot) {
    // The middle state (h_m = cm^2 / g, u_m = 2 (sqrt(g hl) - cm)) moves into hr through a
    // shock: u_m = (h_m - hr) sqrt(g / 2 (h_m + hr) / (h_m hr)).
    const swashes::Stoker s;
    const double hm = s.cm * s.cm / swashes::kG, um = 2.0 * (std::sqrt(swashes::kG * s.hl) - s.cm);
    EXPECT_NEAR(um, (hm - s.hr) * std::sqrt(swashes::kG / 2.0 * (hm + s.hr) / (hm * s.hr)), 1e-12);
}

namespace {

/// A dam break on the flat 10 m strip (open ends) at 100, 200 and 400 cells, to t = 6 s.
template <class Case>
std::vector<Row> dam_break(const Case& s) {
    std::vector<Row> rows;
    for (int n : {100, 200, 400}) {
        ShallowWater w = strip(n, 10.0, [](double) { return 0.0; }, [&](double x) { return s.at(x, 0.0); },
                               {EdgeKind::Open}, {EdgeKind::Open}, true);
        w.advance(6.0);
        rows.push_back(errors_1d(w, [&](double x) { return s.at(x, 6.0); }));
        EXPECT_EQ(w.stats().clipped, 0u);
        // Nothing reaches the ends by 6 s: closed to round-off.
        EXPECT_NEAR(w.balance().error(), 0.0, 1e-12 * w.balance().initial);
    }
    return rows;
}

}  // namespace

TEST(Swashes, StokerDamBreakOnAWetBedConverges) {
    const std::vector<Row> rows = dam_break(swashes::Stoker{});
    const std::vector<double> o = report("Stoker dam break (wet bed)", rows, true);
    // A shock: first order in L1 at best; 0.6 leaves room for the pre-asymptotic range.
    for (double v : o) EXPECT_GT(v, 0.6);
    // 1e-4 m^2 over 10 m: a mean error of 1e-5 m, 0.2 % of hl (the shock smeared over a few cells).
    EXPECT_LT(rows.back().h.l1, 1e-4);
}

TEST(Swashes, RitterDamBreakOnADryBedConverges) {
    const std::vector<double> o = report("Ritter dam break (dry bed)", dam_break(swashes::Ritter{}), true);
    // The dry front (h ~ (x_B - x)^2, a kink in h) bounds the order by 1 (0.96-0.99 here).
    for (double v : o) EXPECT_GT(v, 0.7);
}

namespace {

void steady_bump(const char* name, double q, Edge east, const std::function<double(double)>& exact, double min_order) {
    std::vector<Row> rows;
    for (int n : {50, 100, 200}) {
        ShallowWater w = strip(n, 25.0, swashes::bump,
                               [&](double x) { return swashes::Sample{std::max(exact(25.0) - swashes::bump(x), 0.0) , 0.0}; },
                               {EdgeKind::Discharge, q}, east, true);
        w.advance(200.0);
        rows.push_back(errors_1d(w, [&](double x) { return swashes::Sample{exact(x), q / exact(x)}; }));
        // Steady: the discharge is uniform to within its error norm.
        EXPECT_LT(rows.back().q.linf, 0.05 * q) << name << " n=" << n;
    }
    const std::vector<double> o = report(name, rows, true);
    for (double v : o) EXPECT_GT(v, min_order) << name;
}

}  // namespace

TEST(Swashes, SubcriticalFlowOverABumpConverges) {
    steady_bump("steady flow over a bump, subcritical", 4.42, {EdgeKind::Depth, 2.0},
                [](double x) { return swashes::bump_subcritical(x); }, 1.5);  // smooth: second order (1.95 here)
}

TEST(Swashes, TranscriticalFlowOverABumpConverges) {
    steady_bump("steady flow over a bump, transcritical", 1.53, {EdgeKind::Open},
                [](double x) { return swashes::bump_transcritical(x); }, 1.3);  // the limiter clips at the critical point (1.65-1.79 here)
}

TEST(Swashes, ThackerPlanarSurfaceInAParaboloidConverges) {
    const swashes::Thacker t;
    const double period = 2.0 * M_PI / t.omega();
    std::vector<Row> rows;
    for (int n : {50, 100, 200}) {
        const double dx = t.l / n;
        std::vector<double> z(static_cast<size_t>(n) * n);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) z[static_cast<size_t>(j) * n + i] = t.bed((i + 0.5) * dx, (j + 0.5) * dx);
        ShallowWaterDef def;
        def.second_order = true;
        ShallowWater w(n, n, dx, z, def);
        const double w0 = t.omega();
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double h = t.depth((i + 0.5) * dx, (j + 0.5) * dx, 0.0);
                w.set_state(i, j, h, 0.0, h * t.eta * w0);
            }
        w.balance_reset();
        w.advance(period);
        std::vector<double> eh, eq;
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) {
                const double h = t.depth((i + 0.5) * dx, (j + 0.5) * dx, period);
                eh.push_back(w.depth(i, j) - h);
                eq.push_back(w.discharge_y(i, j) - h * t.eta * w0);
            }
        rows.push_back({n, swashes::norms(eh, dx * dx), swashes::norms(eq, dx * dx)});
        // Closed basin: the volume to round-off (1e-12 of it, summed over the steps).
        EXPECT_NEAR(w.balance().error(), 0.0, 1e-12 * w.balance().initial);
        EXPECT_EQ(w.balance().outflow, 0.0);
    }
    const std::vector<double> o = report("Thacker planar surface (2D, one period)", rows, true);
    // Wetting and drying: the shoreline's cells pull the order from 2 towards 1 (1.47-1.56 here).
    for (double v : o) EXPECT_GT(v, 1.0);
}
