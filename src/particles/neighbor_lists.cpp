// Per-particle neighbour lists (include/metariver/neighbor_grid.h): a count pass and a
// fill pass over each cell run's 27-cell ranges, with an exclusive prefix sum between
// them, so every list holds its neighbours in the ranges' order (the order the
// 27-cell loops of pbf.cpp visit them) whatever the thread count.
#include <metariver/neighbor_grid.h>

#include "grid_runs.h"

#include <tbb/parallel_reduce.h>

namespace mr {

namespace {

/// Candidates of [s, e) within r2 of (x, y, z), over the copies' contiguous x, y, z:
/// a branch-free count (vectorised at -O3).
inline uint32_t count_within(float x, float y, float z, const float* cx, const float* cy, const float* cz,
                             uint32_t s, uint32_t e, float r2) {
    uint32_t c = 0;
    for (uint32_t j = s; j < e; ++j) {
        const float dx = x - cx[j], dy = y - cy[j], dz = z - cz[j];
        c += dx * dx + dy * dy + dz * dz < r2 ? 1u : 0u;
    }
    return c;
}

}  // namespace

void NeighborLists::build(const NeighborGrid& grid, std::span<const Vec3> positions, float reach) {
    ++builds_;
    count_ = grid.order().size();
    start_.resize(count_ + 1);
    const float r2 = reach * reach;
    // Structure-of-arrays copies: the candidate loops read contiguous floats.
    rx_.resize(count_);
    ry_.resize(count_);
    rz_.resize(count_);
    for (size_t i = 0; i < count_; ++i) {
        rx_[i] = positions[i].x;
        ry_[i] = positions[i].y;
        rz_[i] = positions[i].z;
    }
    const float *cx = rx_.data(), *cy = ry_.data(), *cz = rz_.data();
    // Pass 1: counts into start_[i + 1].
    for_each_run(grid, [&](uint32_t i, const Ranges& rg) {
        uint32_t c = 0;
        for (int q = 0; q < rg.n; ++q) c += count_within(cx[i], cy[i], cz[i], cx, cy, cz, rg.s[q], rg.e[q], r2);
        start_[i + 1] = c;
    });
    start_[0] = 0;
    for (size_t i = 0; i < count_; ++i) start_[i + 1] += start_[i];
    index_.resize(start_[count_]);
    // Pass 2: the same test in the same order fills each list.
    for_each_run(grid, [&](uint32_t i, const Ranges& rg) {
        uint32_t* out = index_.data() + start_[i];
        const float x = cx[i], y = cy[i], z = cz[i];
        for (int q = 0; q < rg.n; ++q)
            for (uint32_t j = rg.s[q]; j < rg.e[q]; ++j) {
                const float dx = x - cx[j], dy = y - cy[j], dz = z - cz[j];
                if (dx * dx + dy * dy + dz * dz < r2) *out++ = j;
            }
    });
}

bool NeighborLists::stale(std::span<const Vec3> positions, float skin) const {
    // Max of squared moves, NaN winning (std::max would drop it): exact in any order,
    // so the answer is thread-count independent.
    const auto top = [](float a, float b) { return b > a || b != b ? b : a; };
    const float moved2 = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, count_, 4096), 0.0f,
        [&](const tbb::blocked_range<size_t>& r, float m) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const Vec3 d = positions[i] - Vec3(rx_[i], ry_[i], rz_[i]);
                m = top(m, glm::dot(d, d));
            }
            return m;
        },
        top);
    // Two particles that each moved less than 0.45 skin came closer by less than 0.9 skin.
    const float limit = 0.45f * skin;
    return !(moved2 < limit * limit);
}

}  // namespace mr
