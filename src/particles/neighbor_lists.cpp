// Per-particle neighbour lists (include/metariver/neighbor_grid.h): a count pass and a
// fill pass over each cell run's 27-cell ranges, with an exclusive prefix sum between
// them, so every list holds its neighbours in the ranges' order (the order the
// 27-cell loops of pbf.cpp visit them) whatever the thread count. With AVX2 the count
// pass tests eight candidates at a time and keeps the blocks of eight with one within
// reach, and the fill pass packs those: the scalar build's lists, entry for entry.
#include <metariver/neighbor_grid.h>

#include "grid_runs.h"
#include "simd_offsets.h"

#include <tbb/parallel_reduce.h>

#include <cstring>

#if defined(__x86_64__) && defined(__GNUC__)
#include <immintrin.h>
#define METARIVER_LISTS_AVX2 1
#endif

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

/// Writes i's list to `out`: the candidates within r2, in the ranges' order.
void fill_scalar(uint32_t i, const Ranges& rg, const float* cx, const float* cy, const float* cz, float r2,
                 uint32_t* out) {
    const float x = cx[i], y = cy[i], z = cz[i];
    for (int q = 0; q < rg.n; ++q)
        for (uint32_t j = rg.s[q]; j < rg.e[q]; ++j) {
            const float dx = x - cx[j], dy = y - cy[j], dz = z - cz[j];
            if (dx * dx + dy * dy + dz * dz < r2) *out++ = j;
        }
}

#if METARIVER_LISTS_AVX2
/// Left-packing: for each 8-bit mask, the lanes of its set bits in order, three bits
/// per lane.
struct PackTable {
    uint32_t lanes[256];
    PackTable() {
        for (uint32_t m = 0; m < 256; ++m) {
            uint32_t packed = 0, n = 0;
            for (uint32_t b = 0; b < 8; ++b)
                if (m >> b & 1u) packed |= b << (3 * n++);
            lanes[m] = packed;
        }
    }
};
const PackTable kPack;

// The same test as count_within and the fill's, eight candidates at a time: the
// products and sums in the same order and without fused multiply-adds (no "fma"
// target), so the lists are the scalar build's exactly.
#define MR_LISTS_AVX2 __attribute__((target("avx2,popcnt")))

/// Bits of the candidates j0 .. j0 + 7 (those below e) within r2.
MR_LISTS_AVX2 inline unsigned within8(__m256 x, __m256 y, __m256 z, const float* cx, const float* cy, const float* cz,
                                      uint32_t j0, uint32_t e, __m256 r2) {
    const __m256 d2 = simd::offsets8(x, y, z, cx, cy, cz, j0).d2;
    const unsigned in = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(d2, r2, _CMP_LT_OQ)));
    const uint32_t left = e - j0;
    return left >= 8 ? in : in & ((1u << left) - 1u);
}

/// The count pass of the blocked build: i's blocks of eight candidates that hold one
/// within reach, one word each (j0 | mask << 24; j0 < 2^24), written to `w` without a
/// branch (every block's word is written, the cursor advances past the ones with a
/// mask). Returns the candidates within reach; `listed` gets the words.
MR_LISTS_AVX2 uint32_t count_blocks(uint32_t i, const Ranges& rg, const float* cx, const float* cy, const float* cz,
                                    float reach2, uint32_t* w, uint32_t& listed) {
    const __m256 x = _mm256_set1_ps(cx[i]), y = _mm256_set1_ps(cy[i]), z = _mm256_set1_ps(cz[i]);
    const __m256 r2 = _mm256_set1_ps(reach2);
    uint32_t c = 0, k = 0;
    for (int q = 0; q < rg.n; ++q)
        for (uint32_t j0 = rg.s[q]; j0 < rg.e[q]; j0 += 8) {
            const unsigned m = within8(x, y, z, cx, cy, cz, j0, rg.e[q], r2);
            w[k] = j0 | m << 24;
            k += m != 0;
            c += uint32_t(_mm_popcnt_u32(m));
        }
    listed = k;
    return c;
}

/// The fill pass of the blocked build: i's list from its block words (count_blocks),
/// left-packed eight at a time into a buffer on the stack (a packed store writes all
/// eight lanes, and past the list's end lies the next list, another thread's), with no
/// distance test and no branch per block.
MR_LISTS_AVX2 void fill_blocks(const uint32_t* w, uint32_t listed, uint32_t* out) {
    constexpr uint32_t kBuf = 256;
    alignas(32) uint32_t buf[kBuf + 8];
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i shifts = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
    uint32_t c = 0;
    for (uint32_t k = 0; k < listed; ++k) {
        const uint32_t j0 = w[k] & 0xffffffu, m = w[k] >> 24;
        const __m256i perm =
            _mm256_and_si256(_mm256_srlv_epi32(_mm256_set1_epi32(int(kPack.lanes[m])), shifts), _mm256_set1_epi32(7));
        const __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(int(j0)), _mm256_permutevar8x32_epi32(lane, perm));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(buf + c), idx);
        c += uint32_t(_mm_popcnt_u32(m));
        if (c >= kBuf) {
            std::memcpy(out, buf, kBuf * sizeof(uint32_t));
            out += kBuf;
            c -= kBuf;
            std::memcpy(buf, buf + kBuf, c * sizeof(uint32_t));
        }
    }
    std::memcpy(out, buf, c * sizeof(uint32_t));
}
#endif

/// Blocks of eight over a run's ranges.
uint32_t blocks_of(const Ranges& rg) {
    uint32_t b = 0;
    for (int q = 0; q < rg.n; ++q) b += (rg.e[q] - rg.s[q] + 7) / 8;
    return b;
}

/// A run's ranges in NeighborLists::run_ranges_: the count, then the starts, then the ends.
constexpr size_t kRangesStride = 1 + 2 * 27;

void store_ranges(const Ranges& rg, uint32_t* out) {
    out[0] = uint32_t(rg.n);
    std::memcpy(out + 1, rg.s, size_t(rg.n) * sizeof(uint32_t));
    std::memcpy(out + 28, rg.e, size_t(rg.n) * sizeof(uint32_t));
}

Ranges load_ranges(const uint32_t* in) {
    Ranges rg;
    rg.n = int(in[0]);
    std::memcpy(rg.s, in + 1, size_t(rg.n) * sizeof(uint32_t));
    std::memcpy(rg.e, in + 28, size_t(rg.n) * sizeof(uint32_t));
    return rg;
}

/// f(run) for every cell run of g, in parallel (for_each_run's split).
template <class F>
void for_each_run_index(const NeighborGrid& g, F&& f) {
    parallel_pass(tbb::blocked_range<size_t>(0, g.run_count(), 8), g.order().size(), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t run = range.begin(); run != range.end(); ++run) f(run);
    });
}

}  // namespace

void NeighborLists::build(const NeighborGrid& grid, std::span<const Vec3> positions, float reach) {
    ++builds_;
    count_ = grid.order().size();
    start_.resize(count_ + 1);
    const float r2 = reach * reach;
    // Structure-of-arrays copies: the candidate loops read contiguous floats.
    // (+ 8: the AVX2 passes load eight candidates from the last ones' index.)
    rx_.resize(count_ + 8, 0.0f);
    ry_.resize(count_ + 8, 0.0f);
    rz_.resize(count_ + 8, 0.0f);
    for (size_t i = 0; i < count_; ++i) {
        rx_[i] = positions[i].x;
        ry_[i] = positions[i].y;
        rz_[i] = positions[i].z;
    }
    const float *cx = rx_.data(), *cy = ry_.data(), *cz = rz_.data();
    // Pass 1: counts into start_[i + 1]; pass 2: the same test in the same order fills
    // each list (eight candidates at a time where the CPU has AVX2: the same lists).
    [[maybe_unused]] const bool avx2 = simd_ && avx2_enabled();
#if METARIVER_LISTS_AVX2
    // With AVX2 (and indices below 2^24), the blocked build: the count pass keeps, per
    // particle, the blocks of eight that hold a candidate within reach (about half of
    // them: the 27 cells' corners are empty), and the fill pass packs those without
    // testing a distance again (the fill was 14 % of the 50,000-particle river's
    // profile, the count 4 %). Every particle of a cell run has the same ranges, so a
    // run's block words take (its blocks) x (its particles) slots from a prefix over runs.
    if (avx2 && count_ < (size_t(1) << 24)) {
        const size_t runs = grid.run_count();
        if (ranges_grid_ != grid.build_id() || run_blocks_.size() != runs) {  // else all three still hold
            run_blocks_.resize(runs);
            run_slot_.resize(runs + 1);
            run_ranges_.resize(runs * kRangesStride);
            for_each_run_index(grid, [&](size_t run) {
                const Ranges rg = ranges_of(grid, run);
                store_ranges(rg, run_ranges_.data() + run * kRangesStride);
                run_blocks_[run] = blocks_of(rg);
            });
            run_slot_[0] = 0;
            for (size_t r = 0; r < runs; ++r)
                run_slot_[r + 1] = run_slot_[r] + size_t(run_blocks_[r]) * (grid.run_start(r + 1) - grid.run_start(r));
            ranges_grid_ = grid.build_id();
        }
        words_.resize(run_slot_[runs]);
        listed_.resize(count_);
        for_each_run_index(grid, [&](size_t run) {
            const Ranges rg = load_ranges(run_ranges_.data() + run * kRangesStride);
            const uint32_t b = grid.run_start(run), blocks = run_blocks_[run];
            uint32_t* w = words_.data() + run_slot_[run];
            for (uint32_t i = b; i < grid.run_start(run + 1); ++i, w += blocks)
                start_[i + 1] = count_blocks(i, rg, cx, cy, cz, r2, w, listed_[i]);
        });
        start_[0] = 0;
        for (size_t i = 0; i < count_; ++i) start_[i + 1] += start_[i];
        index_.resize(start_[count_]);
        for_each_run_index(grid, [&](size_t run) {
            const uint32_t b = grid.run_start(run), blocks = run_blocks_[run];
            const uint32_t* w = words_.data() + run_slot_[run];
            for (uint32_t i = b; i < grid.run_start(run + 1); ++i, w += blocks)
                fill_blocks(w, listed_[i], index_.data() + start_[i]);
        });
        return;
    }
#endif
    for_each_run(grid, [&](uint32_t i, const Ranges& rg) {
        uint32_t c = 0;
        for (int q = 0; q < rg.n; ++q) c += count_within(cx[i], cy[i], cz[i], cx, cy, cz, rg.s[q], rg.e[q], r2);
        start_[i + 1] = c;
    });
    start_[0] = 0;
    for (size_t i = 0; i < count_; ++i) start_[i + 1] += start_[i];
    index_.resize(start_[count_]);
    for_each_run(grid, [&](uint32_t i, const Ranges& rg) {
        fill_scalar(i, rg, cx, cy, cz, r2, index_.data() + start_[i]);
    });
}

bool NeighborLists::stale(std::span<const Vec3> positions, float skin) const {
    // Max of squared moves, NaN winning (std::max would drop it): exact in any order,
    // so the answer is thread-count independent.
    const auto top = [](float a, float b) { return b > a || b != b ? b : a; };
    const auto block = [&](const tbb::blocked_range<size_t>& r, float m) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const Vec3 d = positions[i] - Vec3(rx_[i], ry_[i], rz_[i]);
            m = top(m, glm::dot(d, d));
        }
        return m;
    };
    constexpr size_t kGrain = 4096;  // one block (the hybrid's few hundred) runs here, without a task
    const tbb::blocked_range<size_t> all(0, count_, kGrain);
    const float moved2 = count_ <= kGrain ? block(all, 0.0f) : tbb::parallel_reduce(all, 0.0f, block, top);
    // Two particles that each moved less than 0.45 skin came closer by less than 0.9 skin.
    const float limit = 0.45f * skin;
    return !(moved2 < limit * limit);
}

}  // namespace mr
