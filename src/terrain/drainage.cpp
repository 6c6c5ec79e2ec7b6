// The drainage network of a terrain (see drainage.h).
//
// Depression filling: R. Barnes, C. Lehman, D. Mulla, "Priority-Flood: An optimal
// depression-filling and watershed-labeling algorithm for digital elevation models",
// Computers & Geosciences 2014 (the epsilon variant: every filled cell ends strictly
// above the cell it was reached from, so D8 always finds a way down to an edge), the
// flood of priority_flood.h that the conditioning (condition.cpp) runs too.
#include <metariver/drainage.h>

#include "priority_flood.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <utility>

namespace mr {

namespace {

constexpr float kDiagonal = 1.41421356f;

/// The receiver of cell c on the filled surface (a R x C grid): the neighbour of steepest
/// descent (the first in for_neighbours order on ties), -1 where none is lower.
int32_t receiver_of(const std::vector<double>& filled, int R, int C, size_t c) {
    double best = 0.0;
    int32_t r = -1;
    for_neighbours(R, C, c, [&](size_t n, bool diagonal) {
        const double drop = (filled[c] - filled[n]) / (diagonal ? 1.41421356 : 1.0);
        if (drop > best) {
            best = drop;
            r = int32_t(n);
        }
    });
    return r;
}

/// Settles again, after the cells `seeds` changed, a system whose solution is the fixed
/// point val(n) = min(own(n), min over the neighbours m of reach(val(m), n, diagonal))
/// with reach(x, ...) > x (the fill: reach = max(h(n), x + eps), own = h at the border;
/// the distances: reach = x + step, own = 0 on the channel): its solution is unique, so
/// what it settles to is what a build from scratch gives. Every seed and every cell whose
/// value came through one (`from`, the neighbour that gave it) is reset to its own value
/// and to the best its other neighbours give; then Dijkstra from them, which also lowers
/// any other cell a lower value now reaches. `mark`: n zero bytes (zero again on return).
/// Returns the cells whose value or `from` it wrote (with repeats).
template <class T, class Own, class Reach>
std::vector<uint32_t> settle(int R, int C, std::vector<T>& val, std::vector<int32_t>& from, std::vector<uint32_t> seeds,
                             Own&& own, Reach&& reach, std::vector<uint8_t>& mark) {
    std::vector<uint32_t>& reset = seeds;  // grows by the cells whose value came through a reset one
    size_t kept = 0;
    for (const uint32_t c : seeds)
        if (!mark[c]) mark[c] = 1, reset[kept++] = c;
    reset.resize(kept);
    for (size_t q = 0; q < reset.size(); ++q)
        for_neighbours(R, C, reset[q], [&](size_t n, bool) {
            if (!mark[n] && from[n] == int32_t(reset[q])) mark[n] = 1, reset.push_back(uint32_t(n));
        });
    using Item = std::pair<T, uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
    for (const uint32_t c : reset) {
        val[c] = own(c);
        from[c] = -1;
        for_neighbours(R, C, c, [&](size_t m, bool diagonal) {
            if (mark[m]) return;
            const T x = reach(val[m], c, diagonal);
            if (x < val[c]) val[c] = x, from[c] = int32_t(m);
        });
    }
    for (const uint32_t c : reset) {
        mark[c] = 0;
        if (val[c] < std::numeric_limits<T>::infinity()) open.emplace(val[c], c);
    }
    std::vector<uint32_t> written = std::move(reset);
    while (!open.empty()) {
        const T v = open.top().first;  // not a structured binding: clang 15 cannot capture one
        const uint32_t c = open.top().second;
        open.pop();
        if (v != val[c]) continue;  // lowered since it was queued
        for_neighbours(R, C, c, [&](size_t n, bool diagonal) {
            const T x = reach(v, uint32_t(n), diagonal);
            if (x < val[n]) {
                val[n] = x, from[n] = int32_t(c);
                open.emplace(x, uint32_t(n));
                written.push_back(uint32_t(n));
            }
        });
    }
    return written;
}

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
    std::vector<double>& filled = m.filled_;
    filled.resize(n);
    for (int i = 0; i < R; ++i)
        for (int j = 0; j < C; ++j) filled[idx(i, j)] = t.sample(i, j);
    m.lo_ = *std::min_element(filled.begin(), filled.end());
    m.hi_ = *std::max_element(filled.begin(), filled.end());
    const double eps = m.eps_ = std::max(1e-9, (m.hi_ - m.lo_) * 1e-7);
    m.fill_from_.assign(n, -1);
    priority_flood(filled, R, C, [&](size_t c, size_t a, bool) {
        // The first neighbour to reach a cell is its lowest (the flood rises): its fill
        // is max(own height, that neighbour's + eps), update()'s fixed point.
        filled[a] = std::max(filled[a], filled[c] + eps);
        m.fill_from_[a] = int32_t(c);
    });
    // D8 receivers: steepest descent on the filled surface; none at the border's pits.
    m.receiver_.resize(n);
    for (size_t c = 0; c < n; ++c) m.receiver_[c] = receiver_of(filled, R, C, c);
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
    m.dist_from_.assign(n, -1);
    using DItem = std::pair<float, size_t>;
    std::priority_queue<DItem, std::vector<DItem>, std::greater<DItem>> q;
    for (size_t c = 0; c < n; ++c)
        if (m.acc_[c] >= m.threshold_) {
            m.dist_[c] = 0.0f;
            q.emplace(0.0f, c);
        }
    while (!q.empty()) {
        const float d = q.top().first;  // not a structured binding: clang 15 cannot capture one
        const size_t c = q.top().second;
        q.pop();
        if (d > m.dist_[c]) continue;
        for_neighbours(R, C, c, [&](size_t a, bool diagonal) {
            const float nd = d + m.area_scale_ * (diagonal ? kDiagonal : 1.0f);
            if (nd < m.dist_[a]) {
                m.dist_[a] = nd;
                m.dist_from_[a] = int32_t(c);
                q.emplace(nd, a);
            }
        });
    }
    m.find_head_and_outlets();
    return m;
}

void ChannelMap::find_head_and_outlets() {
    const int R = rows_, C = columns_;
    const size_t n = acc_.size();
    // Head of the main channel.
    size_t cur = size_t(std::max_element(acc_.begin(), acc_.end()) - acc_.begin());
    for (;;) {
        size_t next = cur;
        uint32_t best = 0;
        for_neighbours(R, C, cur, [&](size_t c, bool) {
            if (receiver_[c] == int32_t(cur) && acc_[c] >= threshold_ && acc_[c] > best) {
                best = acc_[c];
                next = c;
            }
        });
        if (next == cur) break;
        cur = next;
    }
    head_ = {int(cur / size_t(C)), int(cur % size_t(C))};
    // Outlets: channel cells on the border whose flow leaves the terrain.
    outlets_.clear();
    for (size_t c = 0; c < n; ++c) {
        const int i = int(c / size_t(C)), j = int(c % size_t(C));
        if ((i == 0 || j == 0 || i == R - 1 || j == C - 1) && receiver_[c] < 0 && acc_[c] >= threshold_)
            outlets_.push_back(Outlet{.row = i, .column = j, .accumulation = acc_[c]});
    }
    std::stable_sort(outlets_.begin(), outlets_.end(),
                     [](const Outlet& a, const Outlet& b) { return a.accumulation > b.accumulation; });
}

size_t ChannelMap::update(const Terrain& t, int i0, int i1, int j0, int j1) {
    const int R = rows_, C = columns_;
    const size_t n = size_t(R) * size_t(C);
    if (t.rows() != R || t.columns() != C || t.area_scale() != area_scale_ || filled_.size() != n) {
        *this = build(t);
        return n;
    }
    i0 = std::max(i0, 0), j0 = std::max(j0, 0), i1 = std::min(i1, R - 1), j1 = std::min(j1, C - 1);
    if (i1 < i0 || j1 < j0) return 0;
    // The fill's epsilon comes from the height range: if it moved, every fill did.
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const Vec3& v : t.vertices()) lo = std::min(lo, double(v.y)), hi = std::max(hi, double(v.y));
    if (lo != lo_ || hi != hi_) {
        *this = build(t);
        return n;
    }
    const auto h = [&](uint32_t c) { return double(t.sample(int(c / size_t(C)), int(c % size_t(C)))); };
    const auto border = [&](uint32_t c) {
        const int i = int(c / size_t(C)), j = int(c % size_t(C));
        return i == 0 || j == 0 || i == R - 1 || j == C - 1;
    };
    std::vector<uint8_t> mark(n, 0);

    // 1. The fill: the changed cells are the seeds.
    std::vector<uint32_t> seeds;
    for (int i = i0; i <= i1; ++i)
        for (int j = j0; j <= j1; ++j) seeds.push_back(uint32_t(size_t(i) * size_t(C) + size_t(j)));
    const double eps = eps_;
    const auto fill_written = settle<double>(
        R, C, filled_, fill_from_, seeds,
        [&](uint32_t c) { return border(c) ? h(c) : std::numeric_limits<double>::infinity(); },
        [&](double x, uint32_t c, bool) { return border(c) ? std::numeric_limits<double>::infinity() : std::max(h(c), x + eps); },
        mark);

    // 2. Receivers of the cells whose fill may have changed and of their neighbours.
    std::vector<uint32_t> changed;            // cells whose receiver changed
    std::vector<int32_t> old_receiver;        // their receiver before
    std::vector<uint32_t> visited;           // cells whose receiver was recomputed (marked)
    const auto recompute = [&](uint32_t c) {
        if (mark[c]) return;
        mark[c] = 1;
        visited.push_back(c);
        const int32_t r = receiver_of(filled_, R, C, c);
        if (r != receiver_[c]) changed.push_back(c), old_receiver.push_back(receiver_[c]), receiver_[c] = r;
    };
    for (const uint32_t c : fill_written) {
        recompute(c);
        for_neighbours(R, C, c, [&](size_t m, bool) { recompute(uint32_t(m)); });
    }
    for (const uint32_t c : visited) mark[c] = 0;

    // 3. Accumulation along the old and the new paths below every changed receiver (a cell
    // above none of them keeps its count), upstream first: a receiver is filled lower.
    std::vector<uint32_t> down(changed);
    for (const uint32_t c : changed) mark[c] = 1;
    const auto walk = [&](int32_t c) {
        for (; c >= 0 && !mark[size_t(c)]; c = receiver_[size_t(c)]) {
            mark[size_t(c)] = 1;
            down.push_back(uint32_t(c));
        }
    };
    // Past its first step a path runs through cells whose receiver did not change (a walk
    // stops at a changed one: its own paths are walked) or were walked already.
    for (size_t k = 0; k < changed.size(); ++k) {
        walk(old_receiver[k]);
        walk(receiver_[changed[k]]);
    }
    for (const uint32_t c : down) mark[c] = 0;
    std::stable_sort(down.begin(), down.end(), [&](uint32_t a, uint32_t b) { return filled_[a] > filled_[b]; });
    std::vector<uint32_t> flipped;  // cells that joined or left the channel
    for (const uint32_t c : down) {
        const bool was = acc_[c] >= threshold_;
        uint32_t a = 1;
        for_neighbours(R, C, c, [&](size_t u, bool) {
            if (receiver_[u] == int32_t(c)) a += acc_[u];
        });
        acc_[c] = a;
        if ((a >= threshold_) != was) flipped.push_back(c);
    }

    // 4. Distances from the cells that joined or left the channel.
    size_t written = fill_written.size() + visited.size() + down.size();
    if (!flipped.empty()) {
        const float s = area_scale_;
        written += settle<float>(
                       R, C, dist_, dist_from_, flipped,
                       [&](uint32_t c) { return acc_[c] >= threshold_ ? 0.0f : std::numeric_limits<float>::infinity(); },
                       [&](float x, uint32_t, bool diagonal) { return x + s * (diagonal ? kDiagonal : 1.0f); }, mark)
                       .size();
    }
    find_head_and_outlets();
    return written;
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

}  // namespace mr
