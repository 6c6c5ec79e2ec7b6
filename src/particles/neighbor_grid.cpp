#include <metariver/neighbor_grid.h>

#include <algorithm>
#include <atomic>
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
    static std::atomic<uint64_t> builds{0};
    build_id_ = ++builds;
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
        layout_ = Layout::Dense;
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
    origin_ = box.min;
    const double dense_cells = choose_layout(box, binned);
    cell_keys(positions, active);
    count_buckets(active, dense_cells, binned);
    sort_by_bucket(active, binned);
    record_runs(positions, binned);
}

double NeighborGrid::choose_layout(const Aabb& box, size_t binned) {
    // Dense cells over the box when there are at most ~32 cells per particle and the box
    // is finite (clearing and prefix-summing 32 counters per particle is far cheaper
    // than 27 hash lookups per cell run). Else blocks of 4^3, 8^3 or 16^3 cells (the
    // smallest whose directory has at most ~4 entries per particle), cells allocated
    // only in occupied blocks (at most 64 per particle). Else a hash table of the next
    // power of two >= 2 binned.
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
    const bool fits = std::isfinite(dense_cells) && cells_x <= 0x1FFFFF && cells_y <= 0x1FFFFF && cells_z <= 0x1FFFFF;
    layout_ = Layout::Hashed;
    dims_[0] = dims_[1] = dims_[2] = 0x200000;  // hashed: keys clamped to 21 bits
    if (fits) {
        dims_[0] = int(cells_x);
        dims_[1] = int(cells_y);
        dims_[2] = int(cells_z);
        if (dense_cells <= dense_limit) {
            layout_ = Layout::Dense;
        } else {
            const double dir_limit = std::max(4.0 * double(binned), 4096.0);
            for (int s = 2; s <= 4; ++s) {
                const auto blocks = [&](int c) { return (c + (1 << s) - 1) >> s; };
                if (double(blocks(dims_[0])) * double(blocks(dims_[1])) * double(blocks(dims_[2])) <= dir_limit) {
                    layout_ = Layout::Blocked;
                    shift_ = s;
                    for (int a = 0; a < 3; ++a) nblocks_[a] = blocks(dims_[a]);
                    break;
                }
            }
        }
    }

    return dense_cells;
}

void NeighborGrid::cell_keys(std::span<const Vec3> positions, std::span<const uint8_t> active) {
    const size_t n = positions.size();
    // Cell keys. Binned positions are >= the box's corner, so (v - o) / cell >= 0 and
    // truncation is floor() (the same cell as cell_coord()); clamped to the box (NaN:
    // the last cell).
    {
        const float inv = inv_cell_;
        const Vec3 o = origin_;
        const int hx = dims_[0] - 1, hy = dims_[1] - 1, hz = dims_[2] - 1;
        const float fx = float(hx), fy = float(hy), fz = float(hz);
        const auto c = [](float t, float hf, int h) { return t < hf ? static_cast<int>(t) : h; };
        for (size_t i = 0; i < n; ++i) {
            if (!active[i]) continue;
            const Vec3& q = positions[i];
            const int x = c((q.x - o.x) * inv, fx, hx), y = c((q.y - o.y) * inv, fy, hy), z = c((q.z - o.z) * inv, fz, hz);
            particle_key_[i] = uint64_t(x) | (uint64_t(y) << 21) | (uint64_t(z) << 42);
        }
    }
}

void NeighborGrid::count_buckets(std::span<const uint8_t> active, double dense_cells, size_t binned) {
    const size_t n = active.size();
    const auto kx = [](uint64_t key) { return int(key & 0x1FFFFF); };
    const auto ky = [](uint64_t key) { return int((key >> 21) & 0x1FFFFF); };
    const auto kz = [](uint64_t key) { return int(key >> 42); };
    // Buckets, counted into start_[b] (made inclusive sums below).
    if (layout_ == Layout::Blocked) {
        // Mark the occupied blocks (the directory entry parked in particle_bucket_), give
        // them slots in directory order (spatially coherent, whatever the particle
        // order), then bucket = slot * cells per block + local cell (x fastest).
        const int s = shift_, m = (1 << s) - 1;
        const size_t nbx = size_t(nblocks_[0]), nbxy = nbx * size_t(nblocks_[1]);
        dir_.assign(nbxy * size_t(nblocks_[2]), 0u);
        uint32_t* dir = dir_.data();
        for (size_t i = 0; i < n; ++i) {
            if (!active[i]) continue;
            const uint64_t key = particle_key_[i];
            const size_t d = size_t(kx(key) >> s) + nbx * size_t(ky(key) >> s) + nbxy * size_t(kz(key) >> s);
            particle_bucket_[i] = static_cast<uint32_t>(d);
            dir[d] = 1u;
        }
        uint32_t slots = 0;
        for (uint32_t& d : dir_) d = d != 0u ? slots++ : kNoBlock;
        // Bounded memory: at most 64 cells per particle (always true for 4^3 blocks).
        const size_t cells_needed = size_t(slots) << (3 * s);
        if (cells_needed <= std::max<size_t>(64 * binned, 4096) &&
            cells_needed < size_t(std::numeric_limits<uint32_t>::max())) {
            bucket_count_ = cells_needed;
            start_.assign(bucket_count_ + 1, 0);
            uint32_t* count = start_.data();
            for (size_t i = 0; i < n; ++i) {
                if (!active[i]) continue;
                const uint64_t key = particle_key_[i];
                const uint32_t local = uint32_t(kx(key) & m) | (uint32_t(ky(key) & m) << s) |
                                       (uint32_t(kz(key) & m) << (2 * s));
                const uint32_t b = (dir[particle_bucket_[i]] << (3 * s)) | local;
                particle_bucket_[i] = b;
                ++count[b];
            }
        } else {
            layout_ = Layout::Hashed;  // blocks too sparse: hash (the keys stay valid)
        }
    }
    if (layout_ == Layout::Dense) {
        bucket_count_ = static_cast<size_t>(dense_cells);
        start_.assign(bucket_count_ + 1, 0);
        uint32_t* count = start_.data();
        const uint32_t dx = uint32_t(dims_[0]), dxy = dx * uint32_t(dims_[1]);
        for (size_t i = 0; i < n; ++i) {
            if (!active[i]) continue;
            const uint64_t key = particle_key_[i];
            const uint32_t b = uint32_t(kx(key)) + dx * uint32_t(ky(key)) + dxy * uint32_t(kz(key));
            particle_bucket_[i] = b;
            ++count[b];
        }
    } else if (layout_ == Layout::Hashed) {
        size_t size = 1;
        while (size < 2 * binned) size <<= 1;
        hash_mask_ = static_cast<uint32_t>(size - 1);
        bucket_count_ = size;
        start_.assign(bucket_count_ + 1, 0);
        for (size_t i = 0; i < n; ++i) {
            if (!active[i]) continue;
            const uint64_t key = particle_key_[i];
            const uint32_t b = static_cast<uint32_t>(bucket(kx(key), ky(key), kz(key)));
            particle_bucket_[i] = b;
            ++start_[b];
        }
    }
}

void NeighborGrid::sort_by_bucket(std::span<const uint8_t> active, size_t binned) {
    const size_t n = active.size();
    // Counting sort: inclusive prefix sums give each bucket's end; filling backwards in
    // index order moves them to each bucket's start, ties in index order (stable).
    {
        uint32_t* start = start_.data();
        uint32_t sum = 0;
        size_t b = 0;
        for (; b + 4 <= bucket_count_; b += 4) {  // unrolled: mostly zeros, 1 add + 1 store each
            const uint32_t s0 = sum + start[b], s1 = s0 + start[b + 1], s2 = s1 + start[b + 2];
            sum = s2 + start[b + 3];
            start[b] = s0;
            start[b + 1] = s1;
            start[b + 2] = s2;
            start[b + 3] = sum;
        }
        for (; b < bucket_count_; ++b) {
            sum += start[b];
            start[b] = sum;
        }
        start[bucket_count_] = sum;
        order_.resize(binned);
        uint32_t* order = order_.data();
        for (size_t i = n; i-- > 0;)
            if (active[i]) order[--start[particle_bucket_[i]]] = static_cast<uint32_t>(i);
    }

    // A hash bucket can hold several cells: order each bucket by cell key (stable
    // insertion sort; buckets hold a handful of particles) so every cell is one run.
    if (layout_ == Layout::Hashed) {
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
}

void NeighborGrid::record_runs(std::span<const Vec3> positions, size_t binned) {
    // + kSortedPad finite floats past the last: loops may read a block of 4 or 8 past
    // the end of a range (sorted_x() spans the binned ones only).
    sx_.resize(binned + kSortedPad);
    sy_.resize(binned + kSortedPad);
    sz_.resize(binned + kSortedPad);
    std::fill(sx_.begin() + binned, sx_.end(), 0.0f);
    std::fill(sy_.begin() + binned, sy_.end(), 0.0f);
    std::fill(sz_.begin() + binned, sz_.end(), 0.0f);
    // Cell runs, and the positions in order.
    for (size_t k = 0; k < binned; ++k) {
        const uint32_t i = order_[k];
        const Vec3& q = positions[i];
        sx_[k] = q.x;
        sy_[k] = q.y;
        sz_[k] = q.z;
        const uint64_t key = particle_key_[i];
        if (k == 0 || key != run_key_.back()) {
            run_start_.push_back(static_cast<uint32_t>(k));
            run_key_.push_back(key);
        }
    }
    run_start_.push_back(static_cast<uint32_t>(binned));
    if (layout_ == Layout::Hashed) {  // runs are in bucket order: count per bucket, prefix sum
        bucket_run_start_.assign(bucket_count_ + 1, 0);
        for (size_t q = 0; q + 1 < run_start_.size(); ++q)
            ++bucket_run_start_[particle_bucket_[order_[run_start_[q]]] + 1];
        for (size_t b = 0; b < bucket_count_; ++b) bucket_run_start_[b + 1] += bucket_run_start_[b];
    }
}

}  // namespace mr
