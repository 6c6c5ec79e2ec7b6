#include "lake_crest.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr::swe {

namespace {
/// A flat crest (cells at the spill level) is followed this many cells from the lake at most.
constexpr size_t kFlatReach = 64;

/// The four neighbours of k inside the grid; fewer on the edges.
template <class Visit>
void each_neighbour(const CrestGrid& g, int k, Visit&& visit) {
    const int i = k % g.nx, j = k / g.nx;
    if (i > 0) visit(k - 1);
    if (i + 1 < g.nx) visit(k + 1);
    if (j > 0) visit(k - g.nx);
    if (j + 1 < g.ny) visit(k + g.nx);
}

bool on_edge(const CrestGrid& g, int k) {
    const int i = k % g.nx, j = k / g.nx;
    return i == 0 || j == 0 || i == g.nx - 1 || j == g.ny - 1;
}

/// The largest drop from `from_bed` to a neighbour of k whose level is below `spill` (its
/// water runs on towards the edge without the lake); negative: none.
double drop_out(const CrestGrid& g, int k, double spill, double from_bed) {
    double drop = -1.0;
    each_neighbour(g, k, [&](int q) {
        if (g.level[size_t(q)] < spill) drop = std::max(drop, std::max(from_bed - g.level[size_t(q)], 0.0));
    });
    return drop;
}

/// A rim cell at the spill level: the flat of such cells (outside every lake) from it, walked
/// breadth first up to kFlatReach cells; the slope from the rim cell to the nearest drop out
/// of the flat (infinite where the flat reaches the map's edge); negative: the flat leads
/// nowhere lower (a shore).
double flat_slope(const CrestGrid& g, int rim, double spill) {
    std::vector<int> cells{rim}, steps{0};
    for (size_t at = 0; at < cells.size() && cells.size() <= kFlatReach; ++at) {
        const int c = cells[at];
        if (on_edge(g, c)) return std::numeric_limits<double>::infinity();
        if (const double drop = drop_out(g, c, spill, g.bed[size_t(rim)]); drop >= 0.0)
            return drop / (double(steps[at] + 1) * g.dx);
        each_neighbour(g, c, [&](int q) {
            const bool flat = g.level[size_t(q)] <= spill + g.lake_depth && g.level[size_t(q)] - g.bed[size_t(q)] <= g.lake_depth;
            if (flat && std::find(cells.begin(), cells.end(), q) == cells.end()) {
                cells.push_back(q);
                steps.push_back(steps[at] + 1);
            }
        });
    }
    return -1.0;
}
}  // namespace

std::vector<Crest> find_crests(const CrestGrid& g, std::span<const int> lake, double spill) {
    // The rim: the cells next to the lake not in it. A lake cell's neighbour is in the lake
    // where it stands in water at the flood (neighbouring depression cells share a level).
    std::vector<int> rim;
    for (const int k : lake)
        each_neighbour(g, k, [&](int q) {
            if (g.level[size_t(q)] - g.bed[size_t(q)] <= g.lake_depth) rim.push_back(q);
        });
    std::sort(rim.begin(), rim.end());
    rim.erase(std::unique(rim.begin(), rim.end()), rim.end());
    std::vector<Crest> crests;
    for (const int r : rim) {
        const double bed = g.bed[size_t(r)];
        if (on_edge(g, r)) {  // the water falls off the map
            crests.push_back({r, bed, std::numeric_limits<double>::infinity()});
        } else if (const double drop = drop_out(g, r, spill, bed); drop >= 0.0) {
            crests.push_back({r, bed, drop / g.dx});
        } else if (g.level[size_t(r)] <= spill + g.lake_depth) {  // a flat crest, or a flat shore
            if (const double slope = flat_slope(g, r, spill); slope >= 0.0) crests.push_back({r, bed, slope});
        }
    }
    return crests;
}

double crest_flow(double head, double slope, double manning, double gravity) {
    if (!(head > 0.0)) return 0.0;
    const double c = std::sqrt(gravity * head);  // the lake's wave speed over the crest
    const auto speed = [&](double h) { return std::pow(h, 2.0 / 3.0) * std::sqrt(slope) / manning; };
    double lo = 4.0 / 9.0 * head, hi = head;  // the depth after the crest: critical .. the lake's
    if (!(manning > 0.0) || !std::isfinite(slope) || speed(lo) >= std::sqrt(gravity * lo))
        return 8.0 / 27.0 * c * head;  // Ritter's flux: the flow after the crest is not slower than critical
    for (int it = 0; it < 60 && hi - lo > 1e-12 * head; ++it) {  // sqrt(g H) = sqrt(g h) + u(h) / 2
        const double h = 0.5 * (lo + hi);
        (std::sqrt(gravity * h) + 0.5 * speed(h) > c ? hi : lo) = h;
    }
    const double h = 0.5 * (lo + hi);
    return h * speed(h);
}

double crest_discharge(std::span<const Crest> crests, const CrestGrid& grid, double level) {
    double q = 0.0;
    for (const Crest& c : crests) q += crest_flow(level - c.bed, c.slope, grid.manning, grid.gravity);
    return q * grid.dx;
}

double crest_head(const CrestGrid& g, std::span<const int> lake, double spill, double discharge) {
    if (!(discharge > 0.0)) return 0.0;
    const std::vector<Crest> crests = find_crests(g, lake, spill);
    const auto passes = [&](double h) { return crest_discharge(crests, g, spill + h) >= discharge; };
    double hi = 1e-3;
    while (!passes(hi) && hi < 1e6) hi *= 2.0;
    if (!passes(hi)) return std::numeric_limits<double>::quiet_NaN();  // no crest, or only flat ones under friction
    double lo = 0.0;
    while (hi - lo > 1e-9 * hi) {
        const double mid = 0.5 * (lo + hi);
        (passes(mid) ? hi : lo) = mid;
    }
    return hi;
}

}  // namespace mr::swe
