// The "swe" solver (include/metariver/swe_solver.h): the shallow-water core
// (src/swe/shallow_water.h) on the terrain's grid, shown as a HeightfieldWater.
#include <metariver/drainage.h>
#include <metariver/swe_solver.h>
#include <metariver/terrain.h>

#include "lake_crest.h"
#include "lake_levels.h"
#include "shallow_water.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <queue>

namespace mr {

std::string_view to_string(SweInit i) { return i == SweInit::Steady ? "steady" : "dry"; }
std::string_view to_string(SweEdges e) { return e == SweEdges::Outfall ? "outfall" : "open"; }
std::string_view to_string(SweSourceShape s) { return s == SweSourceShape::Line ? "line" : "point"; }

namespace {

constexpr double kMmPerHour = 1e-3 / 3600.0;  // m/s
/// The least Manning's n the river rule divides by (manning = 0: frictionless).
constexpr double kRuleLeastManning = 0.01;

swe::ShallowWaterDef core_def(const SweDef& d, double gravity) {
    swe::ShallowWaterDef c;
    c.gravity = gravity;
    c.cfl = std::clamp(static_cast<double>(d.cfl), 1e-3, 0.5);
    c.dry_depth = std::max(static_cast<double>(d.dry_depth), 0.0);
    c.manning = std::max(static_cast<double>(d.manning), 0.0);
    c.second_order = d.second_order;
    c.west = c.east = c.south = c.north = {d.edges == SweEdges::Outfall ? swe::EdgeKind::Outfall : swe::EdgeKind::Open};
    return c;
}

/// The cell under (x, z) metres, or (-1, -1) outside the grid.
std::pair<int, int> cell_of(const HeightfieldWater& w, float x, float z) {
    const int i = static_cast<int>(std::lround((x - w.origin.x) / w.spacing));
    const int j = static_cast<int>(std::lround((z - w.origin.z) / w.spacing));
    if (i < 0 || j < 0 || i >= w.columns || j >= w.rows) return {-1, -1};
    return {i, j};
}
/// The grid's cells a segment crosses (sampled every quarter cell, each cell once, in order).
std::vector<std::pair<int, int>> line_cells(const HeightfieldWater& w, Vec3 a, Vec3 b) {
    std::vector<std::pair<int, int>> cells;
    const float len = std::hypot(b.x - a.x, b.z - a.z);
    const int n = std::min(static_cast<int>(std::ceil(4.0f * len / w.spacing)), 1 << 22);
    for (int k = 0; k <= n; ++k) {
        const float t = n > 0 ? float(k) / float(n) : 0.0f;
        const auto c = cell_of(w, a.x + t * (b.x - a.x), a.z + t * (b.z - a.z));
        if (c.first >= 0 && std::find(cells.begin(), cells.end(), c) == cells.end()) cells.push_back(c);
    }
    return cells;
}
/// The cells whose centres lie within r metres of (x, z); the cell under it when none does.
std::vector<std::pair<int, int>> disc_cells(const HeightfieldWater& w, Vec3 c, float r) {
    std::vector<std::pair<int, int>> cells;
    const int reach = static_cast<int>(std::ceil(r / w.spacing)) + 1;
    const auto centre = cell_of(w, c.x, c.z);
    const int ci = static_cast<int>(std::lround((c.x - w.origin.x) / w.spacing));
    const int cj = static_cast<int>(std::lround((c.z - w.origin.z) / w.spacing));
    for (int j = std::max(cj - reach, 0); j <= std::min(cj + reach, w.rows - 1); ++j)
        for (int i = std::max(ci - reach, 0); i <= std::min(ci + reach, w.columns - 1); ++i) {
            const float dx = w.origin.x + float(i) * w.spacing - c.x, dz = w.origin.z + float(j) * w.spacing - c.z;
            if (dx * dx + dz * dz <= r * r) cells.emplace_back(i, j);
        }
    if (cells.empty() && centre.first >= 0) cells.push_back(centre);
    return cells;
}
}  // namespace

Result<std::vector<double>> load_rain_mask(const std::string& path, int columns, int rows) {
    auto image = load_heightmap_png(path);
    if (!image) return Error{fmt::format("swe.rain_mask: {}", image.error().message)};
    const Heightmap& m = image.value();
    if (m.width < 1 || m.height < 1 || m.samples.size() < static_cast<size_t>(m.width) * m.height)
        return Error{fmt::format("swe.rain_mask: '{}' has no pixels", path)};
    // Bilinear over the image stretched to the grid: cell (i, j) at pixel
    // (i (width - 1) / (columns - 1), j (height - 1) / (rows - 1)).
    const auto px = [&](int c, int r) { return double(std::clamp(m.samples[static_cast<size_t>(r) * m.width + c], 0.0f, 1.0f)); };
    std::vector<double> w(static_cast<size_t>(std::max(columns, 0)) * std::max(rows, 0), 0.0);
    for (int j = 0; j < rows; ++j)
        for (int i = 0; i < columns; ++i) {
            const double u = columns > 1 ? double(i) * (m.width - 1) / (columns - 1) : 0.0;
            const double v = rows > 1 ? double(j) * (m.height - 1) / (rows - 1) : 0.0;
            const int c0 = std::min(static_cast<int>(u), m.width - 1), r0 = std::min(static_cast<int>(v), m.height - 1);
            const int c1 = std::min(c0 + 1, m.width - 1), r1 = std::min(r0 + 1, m.height - 1);
            const double fu = u - c0, fv = v - r0;
            w[static_cast<size_t>(j) * columns + i] = (1 - fv) * ((1 - fu) * px(c0, r0) + fu * px(c1, r0)) +
                                                      fv * ((1 - fu) * px(c0, r1) + fu * px(c1, r1));
        }
    return w;
}

SweSolver::SweSolver(const Terrain& terrain, const SweDef& def, Vec3 resolved_source, float gravity)
    : def_(def), source_(resolved_source) {
    const int nx = std::max(terrain.columns(), 1), ny = std::max(terrain.rows(), 1);
    const std::span<const Vec3> v = terrain.vertices();
    std::vector<double> bed(static_cast<size_t>(nx) * ny, 0.0);
    for (size_t k = 0; k < bed.size() && k < v.size(); ++k) bed[k] = v[k].y;
    water_.rows = ny;
    water_.columns = nx;
    water_.origin = v.empty() ? Vec3(0.0f) : v.front();
    water_.spacing = terrain.area_scale();
    water_.depth.assign(water_.size(), 0.0f);
    water_.velocity.assign(water_.size(), Vec3(0.0f));
    water_.wet_first.assign(size_t(ny), nx);  // all dry
    water_.wet_last.assign(size_t(ny), -1);
    core_ = std::make_unique<swe::ShallowWater>(nx, ny, water_.spacing, bed, core_def(def_, gravity > 0.0f && std::isfinite(gravity) ? gravity : 9.81));
    // The main channel from the source's cell (the drainage network's D8 path to the edge):
    // the river rule's slope and the spin-up's time cap.
    const Vec3 c = def_.auto_source ? source_ : def_.source_center;
    const int si = std::clamp(static_cast<int>(std::lround((c.z - water_.origin.z) / water_.spacing)), 0, ny - 1);
    const int sj = std::clamp(static_cast<int>(std::lround((c.x - water_.origin.x) / water_.spacing)), 0, nx - 1);
    const ChannelMap map = ChannelMap::build(terrain);
    std::vector<std::pair<int, int>> path;
    if (!v.empty()) {
        path = map.path_from(si, sj);
        double length = 0.0;
        for (size_t k = 1; k < path.size(); ++k)
            length += water_.spacing * std::hypot(double(path[k].first - path[k - 1].first), double(path[k].second - path[k - 1].second));
        channel_length_ = static_cast<float>(std::max(length, double(water_.spacing)));
        const double drop = path.empty() ? 0.0 : terrain.sample(path.front().first, path.front().second) -
                                                     terrain.sample(path.back().first, path.back().second);
        channel_slope_ = std::max(static_cast<float>(drop / channel_length_), kSweLeastSlope);
    }
    if (std::isfinite(def_.initial_level))
        for (int j = 0; j < ny; ++j) {
            if (std::isfinite(def_.dam_z) && water_.origin.z + static_cast<float>(j) * water_.spacing < def_.dam_z) continue;
            for (int i = 0; i < nx; ++i) core_->set_state(i, j, std::max(def_.initial_level - bed[static_cast<size_t>(j) * nx + i], 0.0));
        }
    core_->balance_reset();
    apply_def();
    if (def_.init == SweInit::Steady) {
        std::vector<std::pair<int, int>> starts;  // (column, row) of every source
        if (discharge_ > 0.0f) starts.emplace_back(sj, si);
        for (const SweSource& s : def_.sources)
            if (const auto c = cell_of(water_, s.start.x, s.start.z); c.first >= 0) starts.push_back(c);
        swe::LakeLevels lakes(fill_depressions(starts));
        core_->balance_reset();
        spin_up(lakes);
    }
    start_time_ = core_->time();
    core_->balance_reset();
    publish();
}

SweSolver::~SweSolver() = default;

void SweSolver::apply_def() {
    core_->set_def(core_def(def_, core_->def().gravity));
    apply_rain();
    time_scale_ = def_.time_scale == kSweAuto ? water_.spacing : std::max(def_.time_scale, 1e-6f);
    // The river rule: uniform Manning flow kSweRiverDepth deep over one cell's width on the
    // main channel's slope, q = h^(5/3) sqrt(S) / n per metre of width.
    const bool other_water = std::isfinite(def_.initial_level) || !def_.sources.empty();
    const double n = std::max(static_cast<double>(def_.manning), kRuleLeastManning);
    const double rule = water_.spacing * std::pow(double(kSweRiverDepth), 5.0 / 3.0) * std::sqrt(double(channel_slope_)) / n;
    discharge_ = def_.discharge == kSweAuto ? (other_water ? 0.0f : static_cast<float>(rule)) : std::max(def_.discharge, 0.0f);
    const Vec3 c = def_.auto_source ? source_ : def_.source_center;
    source_i_ = static_cast<int>(std::lround((c.x - water_.origin.x) / water_.spacing));
    source_j_ = static_cast<int>(std::lround((c.z - water_.origin.z) / water_.spacing));
    const bool inside = source_i_ >= 0 && source_j_ >= 0 && source_i_ < water_.columns && source_j_ < water_.rows;
    std::vector<swe::PointSource> sources;
    if (discharge_ > 0.0f && inside) sources.push_back({source_i_, source_j_, discharge_});
    add_sources(sources);
    core_->set_sources(std::move(sources));
}

void SweSolver::apply_rain() {
    if (!rain_rates_.empty()) {  // set_rain's, over the scene's keys
        std::vector<double> rate(rain_rates_.size());
        for (size_t k = 0; k < rate.size(); ++k) rate[k] = double(rain_rates_[k]) * kMmPerHour;
        core_->set_rain(0.0);
        core_->set_rain_mask(std::move(rate));
        return;
    }
    const double rain = std::max(static_cast<double>(def_.rain), 0.0) * kMmPerHour;
    if (def_.rain_mask != mask_path_) {  // read once per path
        mask_path_ = def_.rain_mask;
        mask_.clear();
        mask_error_.clear();
        if (!mask_path_.empty()) {
            auto m = load_rain_mask(mask_path_, water_.columns, water_.rows);
            if (m) mask_ = std::move(m.value());
            else mask_error_ = m.error().message;
        }
    }
    if (def_.rain_radius > 0.0f || !def_.rain_mask.empty()) {  // rain within the circle, weighed by the mask
        std::vector<double> mask(water_.size(), 0.0);
        const float r2 = def_.rain_radius * def_.rain_radius;
        for (int j = 0; j < water_.rows; ++j)
            for (int i = 0; i < water_.columns; ++i) {
                const float dx = water_.origin.x + float(i) * water_.spacing - def_.rain_center.x;
                const float dz = water_.origin.z + float(j) * water_.spacing - def_.rain_center.z;
                const size_t k = static_cast<size_t>(j) * water_.columns + i;
                const bool in_circle = def_.rain_radius <= 0.0f || dx * dx + dz * dz <= r2;
                const double weight = def_.rain_mask.empty() ? 1.0 : k < mask_.size() ? mask_[k] : 0.0;
                if (in_circle) mask[k] = rain * weight;
            }
        core_->set_rain(0.0);
        core_->set_rain_mask(std::move(mask));
    } else {
        core_->set_rain_mask({});
        core_->set_rain(rain);
    }
}

// [[swe.sources]] (each discharge spread evenly over its cells) and [[swe.sinks]] (a negative
// discharge the core never lets take more than a cell holds).
void SweSolver::add_sources(std::vector<swe::PointSource>& out) const {
    for (const SweSource& s : def_.sources) {
        const auto cells = s.shape == SweSourceShape::Line ? line_cells(water_, s.start, s.end) : disc_cells(water_, s.start, 0.0f);
        for (const auto& [i, j] : cells) out.push_back({i, j, double(s.discharge) / double(cells.size())});
    }
    if (std::isfinite(def_.sea_level))  // the sea: every drop that reaches it (far above any cell's volume a step)
        for (int j = 0; j < water_.rows; ++j)
            for (int i = 0; i < water_.columns; ++i)
                if (core_->bed(i, j) < def_.sea_level) out.push_back({i, j, -1e30});
    for (const SweSink& s : def_.sinks) {
        const auto cells = disc_cells(water_, s.center, s.radius);
        for (const auto& [i, j] : cells) out.push_back({i, j, -double(s.discharge) / double(cells.size())});
    }
}

// swe.init = "steady": first order at the largest CFL, in windows, until what leaves (the
// edges and the sinks) is what comes in (sources and rain) within init_tolerance over two
// windows running; then the scheme asked for (second order holds less water than the first
// order's diffusion) until it is calm again; or the cap: the time cap, and at most
// swe.init_max_work cell updates and one substep per 5000 of them (the work, whatever
// the time asked). The automatic time cap is the larger of kSweInitCrossings channel
// crossings and kSweInitResidences residence times (what the map holds over what comes in
// a second, measured as it fills): a sheet over a flat map or a lake's level settles over
// its residence time, not over the time the water takes to cross. After each window the
// filled lakes whose levels approach their steady ones geometrically are moved to where the
// series ends (swe::LakeLevels): a large lake on the route settles over far more time than
// the cap.
void SweSolver::spin_up(swe::LakeLevels& lakes) {
    const auto t0 = std::chrono::steady_clock::now();
    const swe::ShallowWaterDef asked = core_->def();
    swe::ShallowWaterDef fast = asked;
    fast.second_order = false;
    fast.cfl = 0.5;
    // The channel, or half the map's diagonal where the route is shorter (a flat map's).
    const double reach = std::max(double(channel_length_), 0.5 * water_.spacing * std::hypot(double(water_.columns), double(water_.rows)));
    const bool auto_cap = def_.init_max_time == kSweAuto;
    const double crossings = auto_cap ? kSweInitCrossings * reach / 0.5 : def_.init_max_time;
    const double window = std::max(crossings / 40.0, 1e-3);
    const uint64_t steps0 = core_->stats().substeps, updates0 = core_->stats().cell_updates;
    double cap = crossings;
    const double work = def_.init_max_work, substeps = work / double(kSweInitCellUpdatesPerSubstep);
    const auto work_left = [&] {
        init_.work_capped = double(core_->stats().substeps - steps0) >= substeps || double(core_->stats().cell_updates - updates0) >= work;
        return !init_.work_capped;
    };
    const auto calm_under = [&](const swe::ShallowWaterDef& scheme) {
        core_->set_def(scheme);
        lakes.restart();
        int calm = 0;
        swe::MassBalance prev = core_->balance();
        while (core_->time() < cap && work_left()) {
            core_->advance(window);
            const swe::MassBalance b = core_->balance();
            const double in = (b.inflow - prev.inflow) + (b.rain - prev.rain);
            const double out = (b.outflow - prev.outflow) + (b.sunk - prev.sunk);
            const double tol = def_.init_tolerance * (in > 0.0 ? in : std::max(b.stored, 1e-12));
            init_.outflow_over_inflow = in > 0.0 ? out / in : 0.0;
            calm = std::abs(out - in) <= tol && std::abs(b.stored - prev.stored) <= tol ? calm + 1 : 0;
            prev = b;
            if (auto_cap && in > 0.0) cap = std::max(cap, kSweInitResidences * b.stored / (in / window));
            if (calm >= 2) return true;
            if (lakes.after_window(*core_, tol) > 0) {  // moved: the storage jumped, the next windows decide
                calm = 0;
                prev = core_->balance();
            }
        }
        return false;
    };
    init_.converged = calm_under(fast) && (!asked.second_order || calm_under(asked));
    core_->set_def(asked);
    init_.ran = true;
    init_.simulated_s = core_->time();
    init_.substeps = init_substeps_ = core_->stats().substeps - steps0;
    init_.cell_updates = core_->stats().cell_updates - updates0;
    init_.wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

namespace {
/// The priority flood (Barnes et al. 2014) over the solver's 4-neighbour faces: each cell's
/// spill level (the lowest surface from which water reaches the map's edge through faces,
/// flat over a depression) and the neighbour it was reached from (towards the edge; -1 on
/// the edge). D8's flood (ChannelMap) crosses diagonal passes the faces do not have.
struct Flood4 {
    std::vector<double> level;
    std::vector<int> from;
};
Flood4 flood4(const swe::ShallowWater& core, double sea_level) {
    const int nx = core.nx(), ny = core.ny();
    const size_t n = static_cast<size_t>(nx) * ny;
    Flood4 f{std::vector<double>(n, 0.0), std::vector<int>(n, -1)};
    std::vector<uint8_t> done(n, 0);
    using Item = std::pair<double, int>;  // level, cell: lowest first, ties by index
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i)
            if (i == 0 || j == 0 || i == nx - 1 || j == ny - 1 || core.bed(i, j) < sea_level) {  // edges and the sea drain
                const int k = j * nx + i;
                f.level[size_t(k)] = core.bed(i, j);
                done[size_t(k)] = 1;
                open.emplace(f.level[size_t(k)], k);
            }
    while (!open.empty()) {
        const auto [lv, k] = open.top();
        open.pop();
        const int i = k % nx, j = k / nx;
        const int next[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
        for (const auto& [a, b] : next) {
            if (a < 0 || b < 0 || a >= nx || b >= ny || done[size_t(b) * nx + a]) continue;
            const int q = b * nx + a;
            done[size_t(q)] = 1;
            f.level[size_t(q)] = std::max(core.bed(a, b), lv);
            f.from[size_t(q)] = k;
            open.emplace(f.level[size_t(q)], q);
        }
    }
    return f;
}

/// A 4-neighbour walk over the nx x ny grid from the cells on `stack` (already marked in
/// `seen`): visit(k) for each cell taken (false: the walk does not go on from it), then
/// every unmarked neighbour q of k with go(k, q) is marked and taken.
template <class Visit, class Go>
void walk4(int nx, int ny, std::vector<int>& stack, std::vector<uint8_t>& seen, Visit&& visit, Go&& go) {
    while (!stack.empty()) {
        const int k = stack.back();
        stack.pop_back();
        if (!visit(k)) continue;
        const int i = k % nx, j = k / nx;
        const int next[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
        for (const auto& [a, b] : next) {
            if (a < 0 || b < 0 || a >= nx || b >= ny) continue;
            const int q = b * nx + a;
            if (seen[size_t(q)] || !go(k, q)) continue;
            seen[size_t(q)] = 1;
            stack.push_back(q);
        }
    }
}

/// Every cell the water from `starts` can reach: from a cell, the water runs to each
/// neighbour whose flooded level is not higher (on the bed, or over a full lake); it stops
/// at the sea.
std::vector<int> reachable(const Flood4& f, const swe::ShallowWater& core, const std::vector<std::pair<int, int>>& starts,
                           double sea_level) {
    const int nx = core.nx(), ny = core.ny();
    std::vector<uint8_t> reached(static_cast<size_t>(nx) * ny, 0);
    std::vector<int> cells, stack;
    for (const auto& [i, j] : starts)
        if (!reached[size_t(j) * nx + i]) {
            reached[size_t(j) * nx + i] = 1;
            stack.push_back(j * nx + i);
        }
    walk4(
        nx, ny, stack, reached,
        [&](int k) {
            cells.push_back(k);
            return core.bed(k % nx, k / nx) >= sea_level;
        },
        [&](int k, int q) { return f.level[size_t(q)] <= f.level[size_t(k)]; });
    return cells;
}
}  // namespace

std::vector<swe::Lake> SweSolver::fill_depressions(const std::vector<std::pair<int, int>>& starts) {
    const int nx = water_.columns, ny = water_.rows;
    const double sea = std::isfinite(def_.sea_level) ? double(def_.sea_level) : -HUGE_VAL;
    const Flood4 f = flood4(*core_, sea);
    // Depression cells: the spill level more than a millimetre above the bed.
    const auto low = [&](int k) { return f.level[size_t(k)] - core_->bed(k % nx, k / nx) > 1e-3; };
    // Which depressions hold water at the steady state: every one under rain over the whole
    // map; else every one the sources' water can reach (the flood's own route to the edge is
    // one such path, not always the one water takes: andes_peru's water ran past it).
    const bool rain_everywhere = def_.rain > 0.0f && def_.rain_radius <= 0.0f && def_.rain_mask.empty();
    std::vector<int> seeds;
    if (rain_everywhere)
        for (int k = 0; k < nx * ny; ++k) seeds.push_back(k);
    else
        seeds = reachable(f, *core_, starts, sea);
    // Those on each source's route to the edge (through the spill points) pass its whole
    // discharge: they start at the head over their spill level that passes it over their
    // crest (swe::crest_head: critical flow over a broad crest or Manning's flow on the slope
    // after it, over every cell the water leaves by), so they spill at once instead of
    // approaching the rate over weeks at km cells. So do the side lakes a route lake's
    // outlets feed (swe::route_lakes: the discharge split between each lake's crests):
    // random_1000x700's side lake of 18,708 cells filled at 40 % of the inflow for thousands
    // of simulated seconds from its spill level, a rise the lake levels' extrapolation cannot
    // end; from above, it settles geometrically, which it can. The others take a share and
    // start at their spill level (with the whole head, a noisy map's many side pits drained
    // for hours; random_1000x700's lake of 6,895 cells that no outlet feeds did).
    std::vector<uint8_t> route(static_cast<size_t>(nx) * ny, rain_everywhere ? 1 : 0);
    for (const auto& [i, j] : starts)
        for (int k = j * nx + i; k >= 0; k = f.from[size_t(k)]) route[size_t(k)] = 1;
    double q = discharge_;
    for (const SweSource& s : def_.sources) q += s.discharge;
    // Where a lake has no crest (none found within reach): the weir one cell wide.
    const double one_cell = std::pow(q / (1.705 * water_.spacing), 2.0 / 3.0);
    std::vector<uint8_t> seen(static_cast<size_t>(nx) * ny, 0);
    std::vector<int> stack;
    std::vector<std::vector<int>> cells;  // the depressions (4-connected)
    std::vector<uint8_t> on_route;
    for (const int k0 : seeds) {
        if (seen[size_t(k0)] || !low(k0)) continue;
        seen[size_t(k0)] = 1;
        stack.assign(1, k0);
        cells.emplace_back();
        on_route.push_back(0);
        walk4(
            nx, ny, stack, seen,
            [&](int k) {
                cells.back().push_back(k);
                on_route.back() = on_route.back() || route[size_t(k)];
                return true;
            },
            [&](int, int n) { return low(n); });
    }
    std::vector<double> bed(static_cast<size_t>(nx) * ny);
    for (int k = 0; k < nx * ny; ++k) bed[size_t(k)] = core_->bed(k % nx, k / nx);
    const swe::CrestGrid grid{.nx = nx, .ny = ny, .dx = water_.spacing, .bed = bed, .level = f.level,
                              .manning = core_->def().manning, .gravity = core_->def().gravity};
    std::vector<int> start_cells;
    for (const auto& [i, j] : starts) start_cells.push_back(j * nx + i);
    const std::vector<swe::LakeFlow> fed = rain_everywhere ? std::vector<swe::LakeFlow>(cells.size())
                                                           : swe::route_lakes(grid, cells, f.from, start_cells, q);
    std::vector<swe::Lake> lakes;
    for (size_t l = 0; l < cells.size(); ++l) {
        const std::vector<int>& lake = cells[l];
        double head = 0.0;
        if (on_route[l] || fed[l].inflow > 0.0) {
            head = swe::crest_head(grid, lake, f.level[size_t(lake.front())], q);
            if (!std::isfinite(head)) head = one_cell;
        }
        double spill_depth = 0.0;
        for (const int k : lake) {  // full to its spill level (plus the head on the route)
            const int i = k % nx, j = k / nx;
            const double h = f.level[size_t(k)] + head - core_->bed(i, j);
            if (h > core_->depth(i, j)) core_->set_state(i, j, h);
            spill_depth += f.level[size_t(k)] - core_->bed(i, j);
        }
        lakes.push_back({lake, spill_depth / double(lake.size())});
    }
    return lakes;
}

double SweSolver::simulated_s() const { return core_->time() - start_time_; }

bool SweSolver::set_params(const SweDef& def, Vec3 resolved_source) {
    const bool same_lake = std::isnan(def.initial_level) ? std::isnan(def_.initial_level) : def.initial_level == def_.initial_level;
    const bool same_dam = std::isnan(def.dam_z) ? std::isnan(def_.dam_z) : def.dam_z == def_.dam_z;
    if (!same_lake || !same_dam || def.init != def_.init) return false;
    def_ = def;
    source_ = resolved_source;
    apply_def();
    return true;
}

void SweSolver::publish() {
    // The float view of the core's doubles (depth and depth-averaged velocity), row by row
    // over the core's wet span and the one shown before (which may have dried): outside
    // both, the view holds zeros already. The fastest speed is the root of the largest
    // squared speed (the root is monotonic and correctly rounded: the same float as the
    // largest root), one root a frame instead of one a cell.
    float fastest2 = 0.0f;
    for (int j = 0; j < water_.rows; ++j) {
        const auto [lo, hi] = core_->wet_span(j);
        const int first = std::min(lo, water_.wet_first[size_t(j)]), last = std::max(hi, water_.wet_last[size_t(j)]);
        for (int i = std::max(first, 0); i <= std::min(last, water_.columns - 1); ++i) {
            const size_t k = static_cast<size_t>(j) * water_.columns + i;
            const double h = core_->depth(i, j);
            water_.depth[k] = static_cast<float>(h);
            const bool moving = h > core_->def().dry_depth;
            water_.velocity[k] = moving ? Vec3(static_cast<float>(core_->discharge_x(i, j) / h), 0.0f,
                                               static_cast<float>(core_->discharge_y(i, j) / h))
                                        : Vec3(0.0f);
            fastest2 = std::max(fastest2, glm::dot(water_.velocity[k], water_.velocity[k]));
        }
        water_.wet_first[size_t(j)] = lo <= hi ? lo : water_.columns;
        water_.wet_last[size_t(j)] = lo <= hi ? hi : -1;
    }
    counters_.max_speed = std::sqrt(fastest2);
}

void SweSolver::step_frame(float frame_dt) {
    advance_frame(frame_dt);
    publish();
}

void SweSolver::advance_frame(float frame_dt) {
    const uint64_t before = core_->stats().substeps;
    if (frame_dt > 0.0f && std::isfinite(frame_dt)) core_->advance(double(frame_dt) * time_scale_);
    last_substeps_ = core_->stats().substeps - before;
    counters_.substeps = core_->stats().substeps - init_substeps_;
    counters_.cell_updates = core_->stats().cell_updates;
    ++frame_;
}

SweBalance SweSolver::balance() const {
    const swe::MassBalance b = core_->balance();
    return {.initial = b.initial, .inflow = b.inflow + poured_, .rain = b.rain, .outflow = b.outflow, .sunk = b.sunk,
            .stored = b.stored, .exchanged = b.exchanged};
}

std::vector<std::string> SweSolver::warnings() const {
    std::vector<std::string> w;
    if (discharge_ > 0.0f && (source_i_ < 0 || source_j_ < 0 || source_i_ >= water_.columns || source_j_ >= water_.rows))
        w.push_back(fmt::format("swe.source_center: ({}, {}) lies outside the terrain; swe.discharge pours nothing",
                                def_.auto_source ? source_.x : def_.source_center.x, def_.auto_source ? source_.z : def_.source_center.z));
    for (size_t k = 0; k < def_.sources.size(); ++k) {
        const SweSource& s = def_.sources[k];
        const bool in = s.shape == SweSourceShape::Line ? !line_cells(water_, s.start, s.end).empty()
                                                        : cell_of(water_, s.start.x, s.start.z).first >= 0;
        if (!in) w.push_back(fmt::format("swe.sources[{}]: lies outside the terrain; it pours nothing", k + 1));
    }
    for (size_t k = 0; k < def_.sinks.size(); ++k)
        if (disc_cells(water_, def_.sinks[k].center, def_.sinks[k].radius).empty())
            w.push_back(fmt::format("swe.sinks[{}]: lies outside the terrain; it takes nothing", k + 1));
    if (!mask_error_.empty()) w.push_back(mask_error_ + "; no rain falls");
    if (init_.ran && !init_.converged)
        w.push_back(fmt::format("swe.init: the steady spin-up stopped at its {} cap ({:.4g} s simulated, {} substeps, "
                                "{:.3g} cell updates) with outflow {:.3f} of inflow; raise {}",
                                init_.work_capped ? "work" : "time", init_.simulated_s, init_.substeps, double(init_.cell_updates),
                                init_.outflow_over_inflow,
                                init_.work_capped ? "swe.init_max_work (cell updates; one substep per 5000 of them)"
                                                  : "swe.init_max_time"));
    return w;
}

}  // namespace mr
