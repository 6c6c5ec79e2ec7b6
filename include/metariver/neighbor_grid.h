// metariver neighbour grid: particles binned into cubic cells by a counting sort so
// pair forces only visit the 27 cells around a particle, O(N) instead of the paper's
// O(N^2) all-pairs loop.
//
// Three layouts, chosen per build from the active particles' bounding box:
//  - dense: one bucket per cell of the box (x fastest), when the box has at most ~32
//    cells per particle;
//  - blocked (two-level): a dense directory of coarse blocks (4^3, 8^3 or 16^3 cells)
//    over the box, at most ~4 directory entries per particle, with cells allocated only
//    in the blocks that hold particles: bucket = (block slot, local cell, x fastest),
//    so a neighbour x-row is one range, or two where it crosses a block face;
//  - hashed: a spatial hash into ~2N buckets (bounded memory whatever the spread), when
//    even the coarsest directory or its blocks' cells would be too large. Hash
//    collisions only add candidates: callers always test the real distance.
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
    enum class Layout : uint8_t { Dense, Blocked, Hashed };

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
        for_each_candidate_slot(p, [&](uint32_t k) { f(order_[k]); });
    }

    /// The same walk by slot: f(k) for each position k in order() (the particle is
    /// order()[k], its position at build time sorted_x/y/z()[k]: contiguous per cell, where
    /// the particle arrays are read at random).
    template <class F>
    void for_each_candidate_slot(const Vec3& p, F&& f) const {
        for_each_candidate_range(p, [&](uint32_t b, uint32_t e) {
            for (uint32_t k = b; k < e; ++k) f(k);
        });
    }

    /// The same walk by ranges: f(begin, end) for each range of order() positions that
    /// holds the candidates, in the same order as for_each_candidate_slot. A dense or
    /// blocked grid gives an x-row of three cells as one range (two where it crosses a
    /// block face) and leaves out empty rows, at most 18; hashed: one per bucket, at
    /// most 27. (Eight-wide loops over the ranges fill their lanes better than over
    /// the 27 cells one by one.)
    template <class F>
    void for_each_candidate_range(const Vec3& p, F&& f) const {
        const int cx = cell_coord(p.x, origin_.x), cy = cell_coord(p.y, origin_.y), cz = cell_coord(p.z, origin_.z);
        if (layout_ != Layout::Hashed) {
            uint32_t rs[18], re[18];
            const int n = row_ranges(cx, cy, cz, rs, re);
            for (int k = 0; k < n; ++k) f(rs[k], re[k]);
            return;
        }
        // Hashed: the 27 cells' buckets; two neighbour cells can share one: visit it once.
        uint32_t seen[27];
        int nseen = 0;
        for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dx = -1; dx <= 1; ++dx) {
                    const uint32_t ub = static_cast<uint32_t>(bucket(cx + dx, cy + dy, cz + dz));
                    bool dup = false;
                    for (int s = 0; s < nseen; ++s) dup |= seen[s] == ub;
                    if (dup) continue;
                    seen[nseen++] = ub;
                    if (start_[ub] != start_[ub + 1]) f(start_[ub], start_[ub + 1]);
                }
    }

    float cell_size() const { return cell_; }
    /// Tells builds apart: unique over every grid's builds (0 before the first), so a
    /// cache of something derived from the cells can tell that it still holds.
    uint64_t build_id() const { return build_id_; }
    bool hashed() const { return layout_ == Layout::Hashed; }
    /// The layout the last build() chose.
    Layout layout() const { return layout_; }

    /// Positions of the binned particles in order() order, as separate x, y, z arrays
    /// (as they were at build time): neighbour ranges are contiguous slices of these.
    std::span<const float> sorted_x() const { return {sx_.data(), order_.size()}; }
    std::span<const float> sorted_y() const { return {sy_.data(), order_.size()}; }
    std::span<const float> sorted_z() const { return {sz_.data(), order_.size()}; }
    /// Finite floats (0) the sorted copies hold past their last element, for loops that
    /// read whole blocks of 4 or 8.
    static constexpr size_t kSortedPad = 8;

    /// Runs of binned particles that share one cell, in order(): run r covers
    /// order()[run_start(r) .. run_start(r + 1)). Built by build().
    size_t run_count() const { return run_start_.empty() ? 0 : run_start_.size() - 1; }
    uint32_t run_start(size_t r) const { return run_start_[r]; }
    /// Calls f(begin, end) for each range of order() positions holding the particles of
    /// the 27 cells around cell run r: every such particle exactly once, at most 27
    /// ranges (a dense grid merges the three cells of an x-row into one range, a blocked
    /// one into one or two, and both leave out empty rows; hashed: one range per cell).
    template <class F>
    void for_each_neighbor_range(size_t r, F&& f) const {
        if (layout_ != Layout::Hashed) {
            // The ranges are gathered first by a tight loop (no calls, so its state stays
            // in registers), empty ones dropped, then handed to f.
            uint32_t rs[18], re[18];
            const uint64_t key = run_key_[r];
            const int n = row_ranges(int(key & 0x1FFFFF), int((key >> 21) & 0x1FFFFF), int(key >> 42), rs, re);
            for (int k = 0; k < n; ++k) f(rs[k], re[k]);
            return;
        }
        const uint64_t key = run_key_[r];
        const int cx = int(key & 0x1FFFFF), cy = int((key >> 21) & 0x1FFFFF), cz = int(key >> 42);
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
    static constexpr uint32_t kNoBlock = 0xFFFFFFFFu;
    // build()'s stages, in order: the layout for the binned box (returns its dense cell
    // count), each binned particle's cell key, the buckets counted, the counting sort into
    // order_ (each hash bucket then sorted by key), the sorted positions and cell runs.
    double choose_layout(const Aabb& box, size_t binned);
    void cell_keys(std::span<const Vec3> positions, std::span<const uint8_t> active);
    void count_buckets(std::span<const uint8_t> active, double dense_cells, size_t binned);
    void sort_by_bucket(std::span<const uint8_t> active, size_t binned);
    void record_runs(std::span<const Vec3> positions, size_t binned);

    /// Dense or blocked: the non-empty x-row ranges around cell (cx, cy, cz), which may
    /// lie outside the box (rows outside it are left out), in the 27 cells' order.
    int row_ranges(int cx, int cy, int cz, uint32_t* rs, uint32_t* re) const {
        // Rows clipped to the box: none when the cell is more than one cell outside.
        if (cx < -1 || cy < -1 || cz < -1 || cx > dims_[0] || cy > dims_[1] || cz > dims_[2]) return 0;
        switch (layout_ == Layout::Dense ? 0 : shift_) {
            case 0: return dense_ranges(cx, cy, cz, rs, re);
            case 2: return blocked_ranges<2>(cx, cy, cz, rs, re);
            case 3: return blocked_ranges<3>(cx, cy, cz, rs, re);
            default: return blocked_ranges<4>(cx, cy, cz, rs, re);
        }
    }
    /// Dense: the non-empty x-rows (3 cells, clipped to the box) around cell (cx, cy, cz).
    int dense_ranges(int cx, int cy, int cz, uint32_t* rs, uint32_t* re) const {
        const int nx = dims_[0], ny = dims_[1], nz = dims_[2];
        const int x0 = std::max(cx - 1, 0), x1 = std::min(cx + 1, nx - 1);
        const int y0 = std::max(cy - 1, 0), y1 = std::min(cy + 1, ny - 1);
        const int z0 = std::max(cz - 1, 0), z1 = std::min(cz + 1, nz - 1);
        const size_t sy = size_t(nx), sz = size_t(nx) * size_t(ny), w = size_t(x1 - x0 + 1);
        const uint32_t* const base = start_.data() + size_t(x0);
        int n = 0;
        for (int z = z0; z <= z1; ++z) {
            const uint32_t* row = base + size_t(z) * sz + size_t(y0) * sy;
            for (int y = y0; y <= y1; ++y, row += sy) {
                const uint32_t b = row[0], e = row[w];
                rs[n] = b;
                re[n] = e;
                n += b != e;
            }
        }
        return n;
    }
    /// Blocked with blocks of 2^S cells a side: the non-empty parts of the x-rows
    /// around cell (cx, cy, cz), one per row or two where a row crosses a block face.
    template <int S>
    int blocked_ranges(int cx, int cy, int cz, uint32_t* rs, uint32_t* re) const {
        constexpr int M = (1 << S) - 1;
        const int x0 = std::max(cx - 1, 0), x1 = std::min(cx + 1, dims_[0] - 1);
        const int y0 = std::max(cy - 1, 0), y1 = std::min(cy + 1, dims_[1] - 1);
        const int z0 = std::max(cz - 1, 0), z1 = std::min(cz + 1, dims_[2] - 1);
        const size_t nbx = size_t(nblocks_[0]), nbxy = nbx * size_t(nblocks_[1]);
        const uint32_t* const dir = dir_.data() + (x0 >> S);
        const uint32_t* const start = start_.data();
        const int lx0 = x0 & M, lx1 = x1 & M;
        const bool split = (x1 >> S) != (x0 >> S);  // the row crosses into the next block
        const int end0 = (split ? M : lx1) + 1;
        int n = 0;
        for (int z = z0; z <= z1; ++z) {
            const uint32_t* const dz = dir + size_t(z >> S) * nbxy;
            const uint32_t lz = uint32_t(z & M) << (2 * S);
            for (int y = y0; y <= y1; ++y) {
                const uint32_t* const d = dz + size_t(y >> S) * nbx;
                const uint32_t local = lz | (uint32_t(y & M) << S);
                if (const uint32_t slot = d[0]; slot != kNoBlock) {
                    const uint32_t* const row = start + ((size_t(slot) << (3 * S)) | local);
                    const uint32_t b = row[lx0], e = row[end0];
                    rs[n] = b;
                    re[n] = e;
                    n += b != e;
                }
                if (split) {
                    if (const uint32_t slot = d[1]; slot != kNoBlock) {
                        const uint32_t* const row = start + ((size_t(slot) << (3 * S)) | local);
                        const uint32_t b = row[0], e = row[lx1 + 1];
                        rs[n] = b;
                        re[n] = e;
                        n += b != e;
                    }
                }
            }
        }
        return n;
    }

    int cell_coord(float v, float o) const { return static_cast<int>(std::floor((v - o) * inv_cell_)); }
    /// Bucket of cell (x, y, z), or -1 when a dense or blocked grid has no such cell.
    int64_t bucket(int x, int y, int z) const {
        if (layout_ != Layout::Hashed) {
            if (x < 0 || y < 0 || z < 0 || x >= dims_[0] || y >= dims_[1] || z >= dims_[2]) return -1;
            if (layout_ == Layout::Dense) return x + static_cast<int64_t>(dims_[0]) * (y + static_cast<int64_t>(dims_[1]) * z);
            const int s = shift_, m = (1 << s) - 1;
            const uint32_t slot = dir_[block_index(x >> s, y >> s, z >> s)];
            if (slot == kNoBlock) return -1;
            return (static_cast<int64_t>(slot) << (3 * s)) | ((z & m) << (2 * s)) | ((y & m) << s) | (x & m);
        }
        const uint32_t h = (static_cast<uint32_t>(x) * 73856093u) ^ (static_cast<uint32_t>(y) * 19349663u) ^
                           (static_cast<uint32_t>(z) * 83492791u);
        return h & hash_mask_;
    }
    size_t block_index(int bx, int by, int bz) const {
        return size_t(bx) + size_t(nblocks_[0]) * (size_t(by) + size_t(nblocks_[1]) * size_t(bz));
    }
    float cell_ = 1.0f, inv_cell_ = 1.0f;
    uint64_t build_id_ = 0;
    Vec3 origin_{0.0f};
    int dims_[3] = {0, 0, 0};
    Layout layout_ = Layout::Dense;
    int shift_ = 2;                          // blocked: blocks of 2^shift cells a side
    int nblocks_[3] = {0, 0, 0};             // blocked: directory size
    uint32_t hash_mask_ = 0;
    size_t bucket_count_ = 0;
    std::vector<uint32_t> start_;            // bucket_count + 1
    std::vector<uint32_t> order_;            // binned particle indices by bucket
    std::vector<uint32_t> particle_bucket_;  // per particle (all particles)
    std::vector<uint64_t> particle_key_;     // per particle: packed cell coordinates (21 bits each)
    std::vector<uint32_t> run_start_;        // cell runs over order(), + 1
    std::vector<uint64_t> run_key_;          // the cell of each run
    std::vector<uint32_t> bucket_run_start_; // hashed: runs of bucket b are [start(b), start(b + 1))
    std::vector<uint32_t> dir_;              // blocked: block slot per directory entry, or kNoBlock
    std::vector<uint32_t> scratch_;
    std::vector<uint64_t> key_scratch_;
    std::vector<float> sx_, sy_, sz_;
};

/// Per-particle neighbour lists over a NeighborGrid's cells (compressed rows): for every
/// binned particle i, the particles j of the 27 cells around i's cell that were within
/// `reach` of i when build() ran, in the order NeighborGrid::for_each_neighbor_range
/// visits them (i itself included). Built once per PBF step with reach = h + skin, they
/// stand in for the 27-cell candidates (about 6x as many) in every later pass as long
/// as no particle has moved skin / 2 since the build (Verlet's criterion: then every
/// pair within h now was within h + skin at the build); stale() says when to rebuild.
/// Iterating a list with the same distance test visits the same pairs in the same
/// order as the 27-cell loop, so sums come out bitwise the same (tests check).
class NeighborLists {
public:
    /// Lists of the binned particles of `grid` (indices relabelled: binned particle k
    /// is positions[k]) within `reach` metres. Parallel; the same lists for any thread
    /// count. Reuses its buffers (no allocation once warm).
    void build(const NeighborGrid& grid, std::span<const Vec3> positions, float reach);
    /// True when some binned particle has moved `skin` / 2 or more since build() (with a
    /// 10 % margin for rounding): lists built with reach = h + skin may then miss a pair
    /// within h.
    bool stale(std::span<const Vec3> positions, float skin) const;

    size_t size() const { return count_; }
    std::span<const uint32_t> of(uint32_t i) const {
        return {index_.data() + start_[i], index_.data() + start_[i + 1]};
    }
    /// i's list is index()[first(i) .. first(i + 1)); first(size()) == entries().
    uint32_t first(uint32_t i) const { return start_[i]; }
    const uint32_t* index() const { return index_.data(); }
    /// Total entries (pairs, i with itself included).
    size_t entries() const { return count_ ? start_[count_] : 0; }
    /// Builds since construction (tests and benches read it).
    uint64_t builds() const { return builds_; }
    /// Build with AVX2 where the CPU has it (true, the default) or with the scalar loops
    /// (false): the same lists, entry for entry (the tests build both).
    void set_simd(bool on) { simd_ = on; }

private:
    size_t count_ = 0;
    std::vector<uint32_t> start_;  // count_ + 1
    std::vector<uint32_t> index_;
    std::vector<float> rx_, ry_, rz_;  // positions at the build
    // The AVX2 build's blocks of eight within reach (neighbor_lists.cpp): per cell run
    // its blocks per particle and its first slot in words_; per particle its listed words.
    std::vector<uint32_t> run_blocks_;
    std::vector<size_t> run_slot_;
    std::vector<uint32_t> words_, listed_;
    // Per cell run its neighbour ranges (its count, then the starts and ends at a fixed
    // stride), kept for the grid build they came from (ranges_grid_: its build_id()): a
    // rebuild over the same grid (a PBF step's stale lists) does not gather them again.
    std::vector<uint32_t> run_ranges_;
    uint64_t ranges_grid_ = 0;
    uint64_t builds_ = 0;
    bool simd_ = true;
};

}  // namespace mr
