#include <metariver/neighbor_grid.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr {

void NeighborGrid::relabel_identity() {
    // The caller moved particle order_[k] to index k (binned first, in cell order).
    const size_t m = order_.size();
    scratch_.resize(m);
    key_scratch_.resize(m);
    for (size_t k = 0; k < m; ++k) {
        scratch_[k] = particle_bucket_[order_[k]];
        key_scratch_[k] = particle_key_[order_[k]];
    }
    for (size_t k = 0; k < m; ++k) {
        particle_bucket_[k] = scratch_[k];
        particle_key_[k] = key_scratch_[k];
        order_[k] = static_cast<uint32_t>(k);
    }
}

void NeighborGrid::build(std::span<const Vec3> positions, std::span<const uint8_t> active, float cell_size) {
    const size_t n = positions.size();
    cell_ = cell_size;
    inv_cell_ = 1.0f / cell_size;
    particle_bucket_.resize(n);
    particle_key_.resize(n);
    run_start_.clear();
    run_key_.clear();

    Aabb box;
    size_t binned = 0;
    for (size_t i = 0; i < n; ++i)
        if (active[i]) {
            box.grow(positions[i]);
            ++binned;
        }
    if (binned == 0) {
        hashed_ = false;
        dims_[0] = dims_[1] = dims_[2] = 0;
        bucket_count_ = 0;
        start_.assign(1, 0);
        order_.clear();
        sx_.clear();
        sy_.clear();
        sz_.clear();
        run_start_.push_back(0);
        return;
    }
    // Dense cells over the box when there are at most ~32 cells per particle and the box
    // is finite (clearing and prefix-summing 32 counters per particle is far cheaper
    // than 27 hash lookups per cell run), else a hash table of the next power of two
    // >= 2 binned.
    origin_ = box.min;
    // Same float arithmetic as cell_coord(), so the box's far corner lands in the last cell.
    const auto cells = [&](float hi, float lo) {
        const float c = std::floor((hi - lo) * inv_cell_);
        return std::isfinite(c) ? double(c) + 1.0 : std::numeric_limits<double>::infinity();
    };
    const double cells_x = cells(box.max.x, origin_.x);
    const double cells_y = cells(box.max.y, origin_.y);
    const double cells_z = cells(box.max.z, origin_.z);
    const double dense_cells = cells_x * cells_y * cells_z;
    const double dense_limit = std::max(32.0 * double(binned), 4096.0);
    if (std::isfinite(dense_cells) && dense_cells <= dense_limit && cells_x <= 0x1FFFFF && cells_y <= 0x1FFFFF &&
        cells_z <= 0x1FFFFF) {
        hashed_ = false;
        dims_[0] = int(cells_x);
        dims_[1] = int(cells_y);
        dims_[2] = int(cells_z);
        bucket_count_ = static_cast<size_t>(dense_cells);
    } else {
        hashed_ = true;
        size_t size = 1;
        while (size < 2 * binned) size <<= 1;
        hash_mask_ = static_cast<uint32_t>(size - 1);
        bucket_count_ = size;
    }

    // Counting sort by bucket: count, exclusive prefix sum, fill in index order (stable).
    start_.assign(bucket_count_ + 1, 0);
    for (size_t i = 0; i < n; ++i) {
        if (!active[i]) continue;
        const uint64_t key = cell_key(positions[i]);
        particle_key_[i] = key;
        const uint32_t b = static_cast<uint32_t>(
            bucket(int(key & 0x1FFFFF), int((key >> 21) & 0x1FFFFF), int(key >> 42)));
        particle_bucket_[i] = b;
        ++start_[b + 1];
    }
    for (size_t b = 0; b < bucket_count_; ++b) start_[b + 1] += start_[b];
    order_.resize(binned);
    for (size_t i = 0; i < n; ++i) {
        if (!active[i]) continue;
        order_[start_[particle_bucket_[i]]++] = static_cast<uint32_t>(i);
    }
    for (size_t b = bucket_count_; b > 0; --b) start_[b] = start_[b - 1];
    start_[0] = 0;

    // A hash bucket can hold several cells: order each bucket by cell key (stable
    // insertion sort; buckets hold a handful of particles) so every cell is one run.
    if (hashed_) {
        for (size_t b = 0; b < bucket_count_; ++b) {
            for (uint32_t k = start_[b] + 1; k < start_[b + 1]; ++k) {
                const uint32_t v = order_[k];
                const uint64_t key = particle_key_[v];
                uint32_t m = k;
                while (m > start_[b] && particle_key_[order_[m - 1]] > key) {
                    order_[m] = order_[m - 1];
                    --m;
                }
                order_[m] = v;
            }
        }
    }
    sx_.resize(binned);
    sy_.resize(binned);
    sz_.resize(binned);
    for (size_t k = 0; k < binned; ++k) {
        const Vec3& q = positions[order_[k]];
        sx_[k] = q.x;
        sy_[k] = q.y;
        sz_[k] = q.z;
    }
    // Cell runs.
    for (size_t k = 0; k < binned; ++k) {
        const uint64_t key = particle_key_[order_[k]];
        if (k == 0 || key != run_key_.back()) {
            run_start_.push_back(static_cast<uint32_t>(k));
            run_key_.push_back(key);
        }
    }
    run_start_.push_back(static_cast<uint32_t>(binned));
    if (hashed_) {  // runs are in bucket order: count per bucket, prefix sum
        bucket_run_start_.assign(bucket_count_ + 1, 0);
        for (size_t q = 0; q + 1 < run_start_.size(); ++q)
            ++bucket_run_start_[particle_bucket_[order_[run_start_[q]]] + 1];
        for (size_t b = 0; b < bucket_count_; ++b) bucket_run_start_[b + 1] += bucket_run_start_[b];
    }
}

}  // namespace mr
