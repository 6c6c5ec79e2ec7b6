// Per-particle neighbour lists (include/metariver/neighbor_grid.h): a count pass and a
// fill pass over each cell run's 27-cell ranges, with an exclusive prefix sum between
// them, so every list holds its neighbours in the ranges' order (the order the
// 27-cell loops of pbf.cpp visit them) whatever the thread count.
#include <metariver/neighbor_grid.h>

#include "grid_runs.h"

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
    const __m256 dx = _mm256_sub_ps(x, _mm256_loadu_ps(cx + j0));
    const __m256 dy = _mm256_sub_ps(y, _mm256_loadu_ps(cy + j0));
    const __m256 dz = _mm256_sub_ps(z, _mm256_loadu_ps(cz + j0));
    const __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    const unsigned in = unsigned(_mm256_movemask_ps(_mm256_cmp_ps(d2, r2, _CMP_LT_OQ)));
    const uint32_t left = e - j0;
    return left >= 8 ? in : in & ((1u << left) - 1u);
}

MR_LISTS_AVX2 uint32_t count_avx2(uint32_t i, const Ranges& rg, const float* cx, const float* cy, const float* cz,
                                  float reach2) {
    const __m256 x = _mm256_set1_ps(cx[i]), y = _mm256_set1_ps(cy[i]), z = _mm256_set1_ps(cz[i]);
    const __m256 r2 = _mm256_set1_ps(reach2);
    uint32_t c = 0;
    for (int q = 0; q < rg.n; ++q)
        for (uint32_t j0 = rg.s[q]; j0 < rg.e[q]; j0 += 8)
            c += uint32_t(_mm_popcnt_u32(within8(x, y, z, cx, cy, cz, j0, rg.e[q], r2)));
    return c;
}

/// Writes i's list to `out` (its length is the count pass's): the indices within reach
/// left-packed eight at a time into a buffer on the stack (a packed store writes all
/// eight lanes, and past the list's end lies the next list, another thread's).
MR_LISTS_AVX2 void fill_avx2(uint32_t i, const Ranges& rg, const float* cx, const float* cy, const float* cz,
                             float reach2, uint32_t* out) {
    constexpr uint32_t kBuf = 256;
    alignas(32) uint32_t buf[kBuf + 8];
    const __m256 x = _mm256_set1_ps(cx[i]), y = _mm256_set1_ps(cy[i]), z = _mm256_set1_ps(cz[i]);
    const __m256 r2 = _mm256_set1_ps(reach2);
    const __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const __m256i shifts = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
    uint32_t c = 0;
    for (int q = 0; q < rg.n; ++q)
        for (uint32_t j0 = rg.s[q]; j0 < rg.e[q]; j0 += 8) {
            const unsigned m = within8(x, y, z, cx, cy, cz, j0, rg.e[q], r2);
            if (m == 0) continue;
            const __m256i perm = _mm256_and_si256(
                _mm256_srlv_epi32(_mm256_set1_epi32(int(kPack.lanes[m])), shifts), _mm256_set1_epi32(7));
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
    for_each_run(grid, [&](uint32_t i, const Ranges& rg) {
#if METARIVER_LISTS_AVX2
        if (avx2) {
            start_[i + 1] = count_avx2(i, rg, cx, cy, cz, r2);
            return;
        }
#endif
        uint32_t c = 0;
        for (int q = 0; q < rg.n; ++q) c += count_within(cx[i], cy[i], cz[i], cx, cy, cz, rg.s[q], rg.e[q], r2);
        start_[i + 1] = c;
    });
    start_[0] = 0;
    for (size_t i = 0; i < count_; ++i) start_[i + 1] += start_[i];
    index_.resize(start_[count_]);
    for_each_run(grid, [&](uint32_t i, const Ranges& rg) {
        uint32_t* const out = index_.data() + start_[i];
#if METARIVER_LISTS_AVX2
        if (avx2) return fill_avx2(i, rg, cx, cy, cz, r2, out);
#endif
        fill_scalar(i, rg, cx, cy, cz, r2, out);
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
