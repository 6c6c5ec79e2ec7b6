#include "lake_crest.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <unordered_map>

namespace mr::swe {

namespace {

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

/// The neighbour of k with the lowest level below `spill` (its water runs on towards the
/// edge without the lake); -1: none.
int lowest_out(const CrestGrid& g, int k, double spill) {
    int best = -1;
    each_neighbour(g, k, [&](int q) {
        if (g.level[size_t(q)] < spill && (best < 0 || g.level[size_t(q)] < g.level[size_t(best)])) best = q;
    });
    return best;
}

}  // namespace

std::vector<Crest> find_crests(const CrestGrid& g, std::span<const int> lake, double spill, double most_head) {
    // The water the lake holds at spill + most_head: a priority flood from the lake over
    // every cell not below the spill level (the lake's own cells, its shores, a flat crest,
    // a perched lake under that level) up to grid.most_steps cells from it, each reached at
    // the lowest water level that gets there (the highest level on the lowest way).
    using Item = std::pair<double, int>;  // the level the water reaches the cell at, the cell
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    std::unordered_map<int, int> seen;  // cell, cells from the lake
    for (const int k : lake) seen.emplace(k, 0);
    for (const int k : lake) open.emplace(spill, k);
    const double top = spill + most_head;
    std::vector<Crest> crests;
    while (!open.empty()) {
        const double at = open.top().first;  // not a structured binding: the lambda below
        const int k = open.top().second;      // captures them (clang before 16 refuses that)
        open.pop();
        // A cell of that water next to lower ground (or on the map's edge, where it falls
        // off) is a crest: the water leaves over it.
        if (on_edge(g, k)) crests.push_back({k, at, std::numeric_limits<double>::infinity()});
        else if (const int down = lowest_out(g, k, spill); down >= 0) crests.push_back({k, at, std::max(at - g.level[size_t(down)], 0.0) / g.dx});
        each_neighbour(g, k, [&](int q) {
            const double lv = g.level[size_t(q)];
            const int steps = seen[k] + 1;
            if (lv < spill || lv >= top || steps > g.most_steps || !seen.emplace(q, steps).second) return;
            open.emplace(std::max(at, lv), q);
        });
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
    for (const Crest& c : crests) q += crest_flow(level - c.sill, c.slope, grid.manning, grid.gravity);
    return q * grid.dx;
}

double crest_head(const CrestGrid& g, std::span<const int> lake, double spill, double discharge) {
    if (!(discharge > 0.0)) return 0.0;
    // The water reaches crests up to twice the head one cell's crest needs (Ritter's flux).
    const double one_cell = std::cbrt(std::pow(discharge / (8.0 / 27.0 * std::sqrt(g.gravity) * g.dx), 2.0));
    const std::vector<Crest> crests = find_crests(g, lake, spill, 2.0 * one_cell);
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

std::vector<LakeFlow> route_lakes(const CrestGrid& g, std::span<const std::vector<int>> lakes, std::span<const int> from,
                                  std::span<const int> starts, double discharge) {
    std::vector<LakeFlow> flow(lakes.size());
    std::unordered_map<int, int> lake_of;  // cell, lake
    for (size_t l = 0; l < lakes.size(); ++l)
        for (const int k : lakes[l]) lake_of.emplace(k, int(l));
    const auto pour = [&](int k, int own, double q) {  // down the flood path from k into the first other lake
        for (int steps = 0; k >= 0 && steps <= g.nx * g.ny; k = from[size_t(k)], ++steps)
            if (const auto it = lake_of.find(k); it != lake_of.end() && it->second != own) {
                flow[size_t(it->second)].inflow += q;
                return;
            }
    };
    for (const int k : starts) pour(k, -1, discharge);
    std::vector<size_t> order;  // the highest spill level first: a lake's water only goes lower
    for (size_t l = 0; l < lakes.size(); ++l)
        if (!lakes[l].empty()) order.push_back(l);
    const auto spill = [&](size_t l) { return g.level[size_t(lakes[l].front())]; };
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return spill(a) > spill(b); });
    std::vector<Crest> crests;
    for (const size_t l : order) {
        const double q = flow[l].inflow;
        if (!(q > 0.0)) continue;
        flow[l].head = crest_head(g, lakes[l], spill(l), q);
        if (std::isfinite(flow[l].head)) {  // every outlet under that head, further than the head's own search
            CrestGrid wide = g;
            wide.most_steps = g.route_steps;
            crests = find_crests(wide, lakes[l], spill(l), flow[l].head);
        }
        double total = 0.0;
        if (std::isfinite(flow[l].head))
            for (const Crest& c : crests) total += crest_flow(spill(l) + flow[l].head - c.sill, c.slope, g.manning, g.gravity);
        if (!(total > 0.0)) {  // no crest: all of it over the spill point, down the flood path
            pour(lakes[l].front(), int(l), q);
            continue;
        }
        for (const Crest& c : crests)
            pour(c.cell, int(l), q * crest_flow(spill(l) + flow[l].head - c.sill, c.slope, g.manning, g.gravity) / total);
    }
    return flow;
}

}  // namespace mr::swe
