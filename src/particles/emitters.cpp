// Emitters, sinks and the drainage network of a terrain (see emitters.h).
//
// Depression filling: R. Barnes, C. Lehman, D. Mulla, "Priority-Flood: An optimal
// depression-filling and watershed-labeling algorithm for digital elevation models",
// Computers & Geosciences 2014 (the epsilon variant: every filled cell ends strictly
// above the cell it was reached from, so D8 always finds a way down to an edge).
#include <metariver/emitters.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <tuple>

namespace mr {

std::string_view to_string(SourceShape s) {
    switch (s) {
        case SourceShape::Box: return "box";
        case SourceShape::Disc: return "disc";
        case SourceShape::Point: return "point";
    }
    return "?";
}

std::string_view to_string(SinkKind s) {
    switch (s) {
        case SinkKind::None: return "none";
        case SinkKind::Box: return "box";
        case SinkKind::Edges: return "edges";
    }
    return "?";
}

namespace {
constexpr int kDi[8] = {-1, -1, -1, 0, 0, 1, 1, 1};
constexpr int kDj[8] = {-1, 0, 1, -1, 1, -1, 0, 1};
}  // namespace

ChannelMap ChannelMap::build(const Terrain& t) {
    ChannelMap m;
    const int R = t.rows(), C = t.columns();
    m.rows_ = R;
    m.columns_ = C;
    m.area_scale_ = t.area_scale();
    const size_t n = size_t(R) * size_t(C);
    auto idx = [C](int i, int j) { return size_t(i) * size_t(C) + size_t(j); };

    // Priority flood from the border (double heights: the epsilon must survive large heights).
    std::vector<double> filled(n);
    for (int i = 0; i < R; ++i)
        for (int j = 0; j < C; ++j) filled[idx(i, j)] = t.sample(i, j);
    double lo = *std::min_element(filled.begin(), filled.end()), hi = *std::max_element(filled.begin(), filled.end());
    const double eps = std::max(1e-9, (hi - lo) * 1e-7);
    std::vector<uint8_t> closed(n, 0);
    using Item = std::tuple<double, size_t>;  // (height, index): ties broken by index (deterministic)
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
    for (int i = 0; i < R; ++i)
        for (int j = 0; j < C; ++j)
            if (i == 0 || j == 0 || i == R - 1 || j == C - 1) {
                closed[idx(i, j)] = 1;
                open.emplace(filled[idx(i, j)], idx(i, j));
            }
    while (!open.empty()) {
        const auto [h, c] = open.top();
        open.pop();
        const int i = int(c / size_t(C)), j = int(c % size_t(C));
        for (int k = 0; k < 8; ++k) {
            const int a = i + kDi[k], b = j + kDj[k];
            if (a < 0 || b < 0 || a >= R || b >= C || closed[idx(a, b)]) continue;
            closed[idx(a, b)] = 1;
            filled[idx(a, b)] = std::max(filled[idx(a, b)], h + eps);
            open.emplace(filled[idx(a, b)], idx(a, b));
        }
    }
    // D8 receivers: steepest descent on the filled surface; none at the border's pits.
    m.receiver_.assign(n, -1);
    for (int i = 0; i < R; ++i)
        for (int j = 0; j < C; ++j) {
            double best = 0.0;
            for (int k = 0; k < 8; ++k) {
                const int a = i + kDi[k], b = j + kDj[k];
                if (a < 0 || b < 0 || a >= R || b >= C) continue;
                const double drop = (filled[idx(i, j)] - filled[idx(a, b)]) / ((kDi[k] && kDj[k]) ? 1.41421356 : 1.0);
                if (drop > best) {
                    best = drop;
                    m.receiver_[idx(i, j)] = int32_t(idx(a, b));
                }
            }
        }
    // Accumulation, highest cells first.
    std::vector<uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return filled[a] > filled[b]; });
    m.acc_.assign(n, 1);
    for (uint32_t c : order)
        if (m.receiver_[c] >= 0) m.acc_[size_t(m.receiver_[c])] += m.acc_[c];
    m.threshold_ = std::max<uint32_t>(16, uint32_t(n / 100));

    // Distance to the nearest channel cell (Dijkstra on the 8-neighbour grid, metres).
    m.dist_.assign(n, std::numeric_limits<float>::infinity());
    using DItem = std::pair<float, size_t>;
    std::priority_queue<DItem, std::vector<DItem>, std::greater<DItem>> q;
    for (size_t c = 0; c < n; ++c)
        if (m.acc_[c] >= m.threshold_) {
            m.dist_[c] = 0.0f;
            q.emplace(0.0f, c);
        }
    while (!q.empty()) {
        const auto [d, c] = q.top();
        q.pop();
        if (d > m.dist_[c]) continue;
        const int i = int(c / size_t(C)), j = int(c % size_t(C));
        for (int k = 0; k < 8; ++k) {
            const int a = i + kDi[k], b = j + kDj[k];
            if (a < 0 || b < 0 || a >= R || b >= C) continue;
            const float nd = d + m.area_scale_ * ((kDi[k] && kDj[k]) ? 1.41421356f : 1.0f);
            if (nd < m.dist_[idx(a, b)]) {
                m.dist_[idx(a, b)] = nd;
                q.emplace(nd, idx(a, b));
            }
        }
    }
    // Head of the main channel.
    size_t cur = size_t(std::max_element(m.acc_.begin(), m.acc_.end()) - m.acc_.begin());
    for (;;) {
        const int i = int(cur / size_t(C)), j = int(cur % size_t(C));
        size_t next = cur;
        uint32_t best = 0;
        for (int k = 0; k < 8; ++k) {
            const int a = i + kDi[k], b = j + kDj[k];
            if (a < 0 || b < 0 || a >= R || b >= C) continue;
            const size_t c = idx(a, b);
            if (m.receiver_[c] == int32_t(cur) && m.acc_[c] >= m.threshold_ && m.acc_[c] > best) {
                best = m.acc_[c];
                next = c;
            }
        }
        if (next == cur) break;
        cur = next;
    }
    m.head_ = {int(cur / size_t(C)), int(cur % size_t(C))};
    // Outlets: channel cells on the border whose flow leaves the terrain.
    for (size_t c = 0; c < n; ++c) {
        const int i = int(c / size_t(C)), j = int(c % size_t(C));
        if ((i == 0 || j == 0 || i == R - 1 || j == C - 1) && m.receiver_[c] < 0 && m.acc_[c] >= m.threshold_)
            m.outlets_.push_back(Outlet{.row = i, .column = j, .accumulation = m.acc_[c]});
    }
    std::stable_sort(m.outlets_.begin(), m.outlets_.end(),
                     [](const Outlet& a, const Outlet& b) { return a.accumulation > b.accumulation; });
    return m;
}

std::vector<std::pair<int, int>> ChannelMap::path_from(int i, int j) const {
    std::vector<std::pair<int, int>> path;
    int32_t c = int32_t(size_t(i) * columns_ + j);
    // Receivers lead strictly down the filled surface: no cycle; the bound is a guard.
    for (size_t k = 0; c >= 0 && k < receiver_.size(); ++k) {
        path.emplace_back(c / columns_, c % columns_);
        c = receiver_[size_t(c)];
    }
    return path;
}

std::pair<int, int> ChannelMap::outlet_of(int i, int j) const { return path_from(i, j).back(); }

std::pair<int, int> ChannelMap::nearest_channel_cell(int i, int j) const {
    std::pair<int, int> best{i, j};
    long long best_d = std::numeric_limits<long long>::max();
    for (int a = 0; a < rows_; ++a)
        for (int b = 0; b < columns_; ++b) {
            if (!is_channel(a, b)) continue;
            const long long d = (long long)(a - i) * (a - i) + (long long)(b - j) * (b - j);
            if (d < best_d) {
                best_d = d;
                best = {a, b};
            }
        }
    return best;
}

Vec3 ChannelMap::flow_direction(int i, int j) const {
    const int32_t r = receiver_[size_t(i) * columns_ + j];
    if (r < 0) return Vec3(0.0f);
    const int a = r / columns_, b = r % columns_;
    return glm::normalize(Vec3(float(b - j), 0.0f, float(a - i)));
}

float wet_channel_fraction(const Terrain& t, const ChannelMap& m, std::span<const Vec3> positions,
                           std::span<const uint8_t> active, const WetChannelDef& def) {
    size_t total = 0, wet = 0;
    const float s = t.area_scale();
    for (size_t k = 0; k < positions.size(); ++k) {
        if (!active[k]) continue;
        ++total;
        const Vec3& p = positions[k];
        if (!t.contains_xz(p.x, p.z)) continue;
        const int i = std::clamp(int(std::lround(p.z / s)), 0, t.rows() - 1);
        const int j = std::clamp(int(std::lround(p.x / s)), 0, t.columns() - 1);
        if (m.distance_to_channel(i, j) <= def.width && p.y - t.height_mesh(p.x, p.z) <= def.depth) ++wet;
    }
    return total ? float(double(wet) / double(total)) : 0.0f;
}

void FlowMeter::record(double time_s, uint64_t sunk_total) {
    if (first_outflow_s_ < 0.0 && sunk_total > 0) first_outflow_s_ = time_s;
    const double r[2] = {time_s, double(sunk_total)};
    records_.push(r);
}

FlowMeter::Summary FlowMeter::summary() const {
    Summary s;
    s.first_outflow_s = first_outflow_s_;
    const size_t size = records_.size();
    if (size < 8) return s;
    const size_t last = size - 1, k0 = size / 2;
    auto rate = [&](size_t a, size_t b) {
        const double ta = records_[a][0], tb = records_[b][0];
        return tb > ta ? (records_[b][1] - records_[a][1]) / (tb - ta) : 0.0;
    };
    s.rate = rate(k0, last);
    bool steady = s.rate > 0.0;
    for (int q = 0; q < 4; ++q) {
        const size_t a = k0 + (last - k0) * size_t(q) / 4, b = k0 + (last - k0) * size_t(q + 1) / 4;
        s.windows[q] = rate(a, b);
        steady = steady && std::abs(s.windows[q] - s.rate) <= 0.25 * s.rate;
    }
    s.steady = steady;
    return s;
}

}  // namespace mr
