// metariver neighbour grid: particles binned into cubic cells by a counting sort so
// pair forces only visit the 27 cells around a particle, O(N) instead of the paper's
// O(N^2) all-pairs loop.
//
// Cells are keyed densely over the active particles' bounding box when that box has
// few enough cells (spatially coherent order: x fastest), otherwise by a spatial hash
// into a table of ~2N buckets (bounded memory whatever the spread). Hash collisions
// only add candidates: callers always test the real distance.
#pragma once

#include <metariver/core.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

namespace mr {

class NeighborGrid {
public:
    /// Bins the particles with active[i] != 0 into cells of `cell_size` metres (> 0).
    /// Inactive particles are left out. Reuses its buffers (no allocation once warm).
    void build(std::span<const Vec3> positions, std::span<const uint8_t> active, float cell_size);

    /// After the caller has permuted its particle arrays so that particle order()[k]
    /// now lives at index k, makes the grid refer to the new indices.
    void relabel_identity();

    /// Particle indices ordered by bucket; the particles of bucket b are
    /// order()[start(b) .. start(b + 1)).
    std::span<const uint32_t> order() const { return order_; }
    /// Bucket of a particle index (only for binned particles).
    uint32_t bucket_of(uint32_t particle) const { return particle_bucket_[particle]; }
    size_t bucket_count() const { return bucket_count_; }

    /// Calls f(j) for every binned particle j in the 27 cells around position p
    /// (including p's own particle if binned). Order is deterministic.
    template <class F>
    void for_each_candidate(const Vec3& p, F&& f) const {
        const int cx = cell_coord(p.x, origin_.x), cy = cell_coord(p.y, origin_.y), cz = cell_coord(p.z, origin_.z);
        uint32_t seen[27];
        int nseen = 0;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int64_t b = bucket(cx + dx, cy + dy, cz + dz);
                    if (b < 0) continue;
                    const uint32_t ub = static_cast<uint32_t>(b);
                    if (hashed_) {  // two neighbour cells can share a hash bucket: visit it once
                        bool dup = false;
                        for (int s = 0; s < nseen; ++s) dup |= seen[s] == ub;
                        if (dup) continue;
                        seen[nseen++] = ub;
                    }
                    for (uint32_t k = start_[ub]; k < start_[ub + 1]; ++k) f(order_[k]);
                }
    }

    float cell_size() const { return cell_; }
    bool hashed() const { return hashed_; }

    /// Positions of the binned particles in order() order, as separate x, y, z arrays
    /// (as they were at build time): neighbour ranges are contiguous slices of these.
    std::span<const float> sorted_x() const { return sx_; }
    std::span<const float> sorted_y() const { return sy_; }
    std::span<const float> sorted_z() const { return sz_; }

    /// Runs of binned particles that share one cell, in order(): run r covers
    /// order()[run_start(r) .. run_start(r + 1)). Built by build().
    size_t run_count() const { return run_start_.empty() ? 0 : run_start_.size() - 1; }
    uint32_t run_start(size_t r) const { return run_start_[r]; }
    /// Calls f(begin, end) for each range of order() positions holding the particles of
    /// the 27 cells around cell run r: every such particle exactly once (a dense grid
    /// merges the three cells of an x-row into one range).
    template <class F>
    void for_each_neighbor_range(size_t r, F&& f) const {
        const uint64_t key = run_key_[r];
        const int cx = int(key & 0x1FFFFF), cy = int((key >> 21) & 0x1FFFFF), cz = int(key >> 42);
        if (!hashed_) {
            const int x0 = std::max(cx - 1, 0), x1 = std::min(cx + 1, dims_[0] - 1);
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy) {
                    const int64_t b0 = bucket(x0, cy + dy, cz + dz);
                    if (b0 < 0) continue;
                    const int64_t b1 = b0 + (x1 - x0);
                    f(start_[size_t(b0)], start_[size_t(b1) + 1]);
                }
            return;
        }
        // Hashed: each neighbour cell is found as the run with its exact key among the
        // runs of its bucket, so no cell is visited twice and no foreign cell is visited.
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const int x = cx + dx, y = cy + dy, z = cz + dz;
                    if (x < 0 || y < 0 || z < 0 || x > 0x1FFFFF || y > 0x1FFFFF || z > 0x1FFFFF) continue;
                    const uint64_t want = uint64_t(x) | (uint64_t(y) << 21) | (uint64_t(z) << 42);
                    const uint32_t ub = static_cast<uint32_t>(bucket(x, y, z));
                    for (uint32_t q = bucket_run_start_[ub]; q < bucket_run_start_[ub + 1]; ++q) {
                        if (run_key_[q] == want) {
                            f(run_start_[q], run_start_[q + 1]);
                            break;
                        }
                    }
                }
    }

private:
    int cell_coord(float v, float o) const { return static_cast<int>(std::floor((v - o) * inv_cell_)); }
    uint64_t cell_key(const Vec3& p) const {
        // Coordinates relative to the box's corner are >= 0; 21 bits each (clamped: a
        // cloud 2M cells wide only merges far cells, which distance tests separate).
        const auto c = [](int v) { return static_cast<uint64_t>(std::clamp(v, 0, 0x1FFFFF)); };
        return c(cell_coord(p.x, origin_.x)) | (c(cell_coord(p.y, origin_.y)) << 21) |
               (c(cell_coord(p.z, origin_.z)) << 42);
    }
    /// Bucket of cell (x, y, z), or -1 when a dense grid has no such cell.
    int64_t bucket(int x, int y, int z) const {
        if (!hashed_) {
            if (x < 0 || y < 0 || z < 0 || x >= dims_[0] || y >= dims_[1] || z >= dims_[2]) return -1;
            return x + static_cast<int64_t>(dims_[0]) * (y + static_cast<int64_t>(dims_[1]) * z);
        }
        const uint32_t h = (static_cast<uint32_t>(x) * 73856093u) ^ (static_cast<uint32_t>(y) * 19349663u) ^
                           (static_cast<uint32_t>(z) * 83492791u);
        return h & hash_mask_;
    }

    float cell_ = 1.0f, inv_cell_ = 1.0f;
    Vec3 origin_{0.0f};
    int dims_[3] = {0, 0, 0};
    bool hashed_ = false;
    uint32_t hash_mask_ = 0;
    size_t bucket_count_ = 0;
    std::vector<uint32_t> start_;            // bucket_count + 1
    std::vector<uint32_t> order_;            // binned particle indices by bucket
    std::vector<uint32_t> particle_bucket_;  // per particle (all particles)
    std::vector<uint64_t> particle_key_;     // per particle: packed cell coordinates (21 bits each)
    std::vector<uint32_t> run_start_;        // cell runs over order(), + 1
    std::vector<uint64_t> run_key_;          // the cell of each run
    std::vector<uint32_t> bucket_run_start_; // hashed: runs of bucket b are [start(b), start(b + 1))
    std::vector<uint32_t> scratch_;
    std::vector<uint64_t> key_scratch_;
    std::vector<float> sx_, sy_, sz_;
};

}  // namespace mr
