// metariver field: sparse block field built by gathering compact kernels.
//
// Build, in four steps (see sparse_field.h for the layout):
//   1. Each ball's sample box: the samples within its support radius, widened by
//      floor/ceil and clipped to the grid.
//   2. Counting sort of (ball, block) pairs: count per block, prefix sum, fill in ball
//      order, so each block's list holds its balls in ascending index.
//   3. Slots for the non-empty blocks, in block order, in a pool reused across builds.
//   4. tbb::parallel_for over those blocks: zero the block, then for each of its balls
//      add the kernel over the ball's rows inside the block. The x loop always runs over
//      the block's 8 samples with a r^2 < support^2 mask (fixed trip count, no branches:
//      the compiler turns it into SIMD); rows whose y/z distance alone is outside the
//      support are skipped. Each block is written by one task only and sums its balls in
//      index order, so the values do not depend on the thread count or the schedule.
// Sample positions are origin + spacing * index in float, exactly as ScalarGrid::position.
#include <metariver/sparse_field.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <unordered_map>

namespace mr {

namespace {

constexpr int B = SparseField::kBlock;

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

bool finite(const Vec3& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }

// The x loop runs over a block row of 8 samples as SIMD vectors written with GCC/Clang
// vector extensions, so the SIMD form does not depend on the auto-vectoriser's mood (-O2
// left the poly6 loop scalar): two 4-lane halves by default (SSE2 on x86-64, NEON on
// arm64, scalar code elsewhere), one 8-lane vector in a copy compiled for AVX2 and picked
// at run time on x86-64 CPUs that have it (the default build stays portable). Both give
// the same values: each lane sees the same IEEE operations.
// Every function taking or returning an 8-lane vector is always inlined, so GCC's note
// that such arguments pass differently with and without AVX (-Wpsabi) does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"
using F4 = float __attribute__((vector_size(16)));
using I4 = int __attribute__((vector_size(16)));
using F8 = float __attribute__((vector_size(32)));
using I8 = int __attribute__((vector_size(32)));

template <class V>
[[gnu::always_inline]] inline V load_v(const float* p) {
    V v;
    std::memcpy(&v, p, sizeof v);
    return v;
}
template <class V>
[[gnu::always_inline]] inline void store_v(float* p, V v) {
    std::memcpy(p, &v, sizeof v);
}
template <class V, class M>
[[gnu::always_inline]] inline V select_v(M mask, V a) {  // mask ? a : 0, lane by lane
    return reinterpret_cast<V>(reinterpret_cast<M>(a) & mask);
}
inline F4 load4(const float* p) { return load_v<F4>(p); }

/// W1: max(0, S / (r^2 + 1e-6) - SUB), as kernel_value.
struct W1Eval {
    float s, sub;
    template <class V>
    [[gnu::always_inline]] V operator()(V d2) const {
        const V v = s / (d2 + 1e-6f) - sub;
        return select_v(v > 0.0f, v);
    }
};

/// Poly6: A (1 - r^2 / R^2)^3, as kernel_value (the caller masks r^2 >= R^2).
struct Poly6Eval {
    float amplitude, inv_r2;
    template <class V>
    [[gnu::always_inline]] V operator()(V d2) const {
        const V q = 1.0f - d2 * inv_r2;
        return amplitude * (q * q * q);
    }
};

/// Adds the kernel of the balls of one block (in list order) into `out` (512 floats,
/// zeroed here). i0, j0, k0: the block's first sample. V: the vector type of a row part.
///
/// Each (ball, block) pair runs over every sample row of the ball's box clipped to the
/// block; the lanes beyond the support are masked to +0, which leaves each sum as it was
/// (the values are >= 0, and the balls are added in list order). Narrowing the rows to the
/// support's disc, layer by layer, did less work but took longer: the loops ran a
/// different length at every layer, and the mispredicted exits and a square root per
/// layer cost more than the masked rows (W1 N=10000 R=128: field 7.2 -> 4.5 ms; the PBF
/// river at 16,000: 4.3 -> 2.8 ms). Narrowing once per pair to the part of the support
/// the block's nearest samples reach was slower again (4.5 -> 4.8 ms on W1).
template <class V, class Kernel, class Box>
[[gnu::always_inline]] inline void splat_block_impl(const SampleGrid& g, const Vec3* balls, const uint32_t* list,
                                                    size_t count, const Box* boxes, float sup2, Kernel kernel, int i0,
                                                    int j0, int k0, float* out) {
    constexpr int W = sizeof(V) / sizeof(float);
    constexpr int H = B / W;  // vectors per row
    std::fill(out, out + SparseField::kBlockSamples, 0.0f);
    float xs[B], ys[B], zs[B];
    for (int i = 0; i < B; ++i) {
        xs[i] = g.origin.x + g.spacing * static_cast<float>(i0 + i);
        ys[i] = g.origin.y + g.spacing * static_cast<float>(j0 + i);
        zs[i] = g.origin.z + g.spacing * static_cast<float>(k0 + i);
    }
    for (size_t n = 0; n < count; ++n) {
        const uint32_t b = list[n];
        const Vec3 c = balls[b];
        const Box& box = boxes[b];
        const int ka = std::max(box.k0, k0) - k0, kb = std::min(box.k1, k0 + B - 1) - k0;
        const int ja = std::max(box.j0, j0) - j0, jb = std::min(box.j1, j0 + B - 1) - j0;
        V dx2[H];
        for (int h = 0; h < H; ++h) {
            const V dx = load_v<V>(xs + W * h) - c.x;
            dx2[h] = dx * dx;
        }
        float dy2[B];
        for (int j = ja; j <= jb; ++j) {
            const float dy = ys[j] - c.y;
            dy2[j] = dy * dy;
        }
        for (int k = ka; k <= kb; ++k) {
            const float dz = zs[k] - c.z;
            const float dz2 = dz * dz;
            float* layer = out + B * B * k;
            for (int j = ja; j <= jb; ++j) {
                const float dyz2 = dy2[j] + dz2;
                float* row = layer + B * j;
                for (int h = 0; h < H; ++h) {
                    // Lanes masked by r^2 < support^2 (the box is widened, never narrowed).
                    const V d2 = dx2[h] + dyz2;
                    store_v(row + W * h, load_v<V>(row + W * h) + select_v(d2 < sup2, kernel(d2)));
                }
            }
        }
    }
}

template <class Kernel, class Box>
void splat_block(const SampleGrid& g, const Vec3* balls, const uint32_t* list, size_t count, const Box* boxes,
                 float sup2, Kernel kernel, int i0, int j0, int k0, float* out) {
    splat_block_impl<F4>(g, balls, list, count, boxes, sup2, kernel, i0, j0, k0, out);
}

#if defined(__x86_64__) && defined(__GNUC__)
#define METARIVER_FIELD_AVX2 1
template <class Kernel, class Box>
__attribute__((target("avx2"))) void splat_block_avx2(const SampleGrid& g, const Vec3* balls, const uint32_t* list,
                                                      size_t count, const Box* boxes, float sup2, Kernel kernel,
                                                      int i0, int j0, int k0, float* out) {
    splat_block_impl<F8>(g, balls, list, count, boxes, sup2, kernel, i0, j0, k0, out);
}

#endif

/// Block (bi, bj, bk) of directory index blk, in a directory bx blocks wide and by high.
std::array<int, 3> block_coords(size_t blk, int bx, int by) {
    return {static_cast<int>(blk % static_cast<size_t>(bx)),
            static_cast<int>((blk / static_cast<size_t>(bx)) % static_cast<size_t>(by)),
            static_cast<int>(blk / (static_cast<size_t>(bx) * static_cast<size_t>(by)))};
}

/// Smallest and largest of a block's 512 samples.
void block_range(const float* v, float& lo, float& hi) {
    F4 mn = load4(v), mx = mn;
    for (int n = 4; n < SparseField::kBlockSamples; n += 4) {
        const F4 x = load4(v + n);
        mn = x < mn ? x : mn;
        mx = x > mx ? x : mx;
    }
    lo = std::min(std::min(mn[0], mn[1]), std::min(mn[2], mn[3]));
    hi = std::max(std::max(mx[0], mx[1]), std::max(mx[2], mx[3]));
}

}  // namespace

void SparseField::clear_grid() {
    grid_ = SampleGrid{};
    bx_ = by_ = bz_ = 0;
    allocated_ = 0;
}

Result<SampleGrid> grid_around(std::span<const Vec3> balls, float resolution, float offset, size_t max_samples) {
    if (!std::isfinite(resolution) || !(resolution > 0.0f) || !std::isfinite(offset) || offset < 0.0f) {
        return Error{"grid_around: resolution must be finite and > 0 samples per metre, offset finite and >= 0 metres"};
    }
    SampleGrid g;
    g.spacing = 1.0f / resolution;
    if (balls.empty()) return g;
    Aabb box;
    for (const Vec3& b : balls) {
        if (!finite(b)) return Error{"grid_around: a ball position is not finite"};
        box.grow(b);
    }
    box.min -= Vec3(offset);
    box.max += Vec3(offset);
    const Vec3 ext = box.extent();
    // Same rule and arithmetic as compute_field_paper: ceil(extent * resolution) + 1.
    const auto samples = [&](float e) { return static_cast<double>(std::ceil(e * resolution)) + 1.0; };
    const double nx = samples(ext.x), ny = samples(ext.y), nz = samples(ext.z);
    if (!(nx * ny * nz <= static_cast<double>(max_samples))) {
        return Error{"grid_around: the grid would have " + std::to_string(nx * ny * nz) + " samples, more than the cap " +
                     std::to_string(max_samples)};
    }
    g.origin = box.min;
    g.nx = static_cast<int>(nx);
    g.ny = static_cast<int>(ny);
    g.nz = static_cast<int>(nz);
    return g;
}

size_t keep_balls_within_cap(std::vector<Vec3>& balls, float resolution, float offset, size_t max_samples) {
    if (grid_around(balls, resolution, offset, max_samples)) return 0;  // fits (or an error build() reports)
    // The cube's side in metres: (side x resolution + 1)^3 samples at most, less the offsets.
    const double side = 0.9 * ((std::cbrt(double(max_samples)) - 1.0) / double(resolution) - 2.0 * double(offset));
    if (!(side > 0.0) || !std::isfinite(resolution)) return 0;
    // The most balls in a cell of half the side (a 64-bit key of the cell's three indices).
    const double cell = 0.5 * side;
    const auto key = [&](const Vec3& b) {
        const auto q = [&](float v) { return uint64_t(int64_t(std::floor(double(v) / cell)) & 0x1fffff); };
        return q(b.x) | q(b.y) << 21 | q(b.z) << 42;
    };
    std::unordered_map<uint64_t, uint32_t> count;
    uint64_t best = 0;
    uint32_t most = 0;
    for (const Vec3& b : balls) {
        if (!finite(b)) return 0;  // build() names it
        const uint32_t n = ++count[key(b)];
        if (n > most) most = n, best = key(b);
    }
    glm::dvec3 mean(0.0);
    for (const Vec3& b : balls)
        if (key(b) == best) mean += glm::dvec3(b);
    const Vec3 centre = Vec3(mean / double(most));
    const float half = static_cast<float>(0.5 * side);
    const size_t before = balls.size();
    std::erase_if(balls, [&](const Vec3& b) {
        const Vec3 d = glm::abs(b - centre);
        return d.x > half || d.y > half || d.z > half;
    });
    return before - balls.size();
}

Status SparseField::build(std::span<const Vec3> balls, const SparseFieldDef& def) {
    const auto t0 = std::chrono::steady_clock::now();
    clear_grid();
    stats_ = SparseFieldStats{};
    if (Status s = validate(def.kernel); !s) return s;
    for (size_t b = 0; b < balls.size(); ++b) {
        if (!finite(balls[b])) return Error{"sparse field: ball " + std::to_string(b) + " is not finite"};
    }
    if (balls.size() >= std::numeric_limits<uint32_t>::max()) return Error{"sparse field: too many balls"};

    Result<SampleGrid> grid = build_grid(balls, def);
    if (!grid) return grid.error();
    const SampleGrid g = *grid;
    const int bx = (g.nx + B - 1) / B, by = (g.ny + B - 1) / B, bz = (g.nz + B - 1) / B;
    const size_t nblocks = static_cast<size_t>(bx) * by * bz;
    if (nblocks >= static_cast<size_t>(std::numeric_limits<int32_t>::max())) {
        return Error{"sparse field: too many blocks"};
    }
    Result<double> ball_blocks = ball_boxes(balls, g, def);
    if (!ball_blocks) return ball_blocks.error();
    const double pairs = *ball_blocks;

    grid_ = g;
    bx_ = bx;
    by_ = by;
    bz_ = bz;
    directory_.resize(nblocks);
    std::fill(directory_.begin(), directory_.end(), kNoBlock);
    stats_.balls = balls.size();
    stats_.blocks = nblocks;
    stats_.ball_blocks = static_cast<size_t>(pairs);
    if (nblocks == 0 || balls.empty()) {
        stats_.ms_bin = ms_since(t0);
        return Ok{};
    }
    const size_t slots = bin_balls(nblocks);
    stats_.ms_bin = ms_since(t0);
    splat_blocks(balls, def.kernel, slots);
    return Ok{};
}

Result<SampleGrid> SparseField::build_grid(std::span<const Vec3> balls, const SparseFieldDef& def) const {
    SampleGrid g;
    if (def.domain == DomainMode::BallBounds) {
        Result<SampleGrid> r = grid_around(balls, def.resolution, def.bounds_offset, def.max_samples);
        if (!r) return r.error();
        g = *r;
    } else {
        g = def.box;
        if (!finite(g.origin) || !std::isfinite(g.spacing) || !(g.spacing > 0.0f) || g.nx < 0 || g.ny < 0 || g.nz < 0) {
            return Error{"sparse field: the fixed box needs a finite origin, spacing > 0 metres and sample counts >= 0"};
        }
        if (!(static_cast<double>(g.nx) * g.ny * g.nz <= static_cast<double>(def.max_samples))) {
            return Error{"sparse field: the fixed box has more samples than the cap " + std::to_string(def.max_samples)};
        }
    }

    return g;
}

Result<double> SparseField::ball_boxes(std::span<const Vec3> balls, const SampleGrid& g, const SparseFieldDef& def) {
    // 1. Sample boxes, and the (ball, block) pair count before anything is sized by it.
    const float radius = def.kernel.radius;
    boxes_.resize(balls.size());
    double pairs = 0.0;
    const auto sample_range = [&](float c, float o, int n, int& lo, int& hi) {
        // Widened by floor/ceil; clipped in float first so the int conversion cannot overflow.
        const float a = std::floor((c - radius - o) / g.spacing);
        const float b = std::ceil((c + radius - o) / g.spacing);
        lo = static_cast<int>(std::clamp(a, -1.0f, static_cast<float>(n)));
        hi = static_cast<int>(std::clamp(b, -1.0f, static_cast<float>(n)));
        lo = std::max(lo, 0);
        hi = std::min(hi, n - 1);
    };
    for (size_t b = 0; b < balls.size(); ++b) {
        BallBox& box = boxes_[b];
        sample_range(balls[b].x, g.origin.x, g.nx, box.i0, box.i1);
        sample_range(balls[b].y, g.origin.y, g.ny, box.j0, box.j1);
        sample_range(balls[b].z, g.origin.z, g.nz, box.k0, box.k1);
        if (box.i0 > box.i1 || box.j0 > box.j1 || box.k0 > box.k1) {
            box.i0 = 0;
            box.i1 = -1;  // misses the grid
            continue;
        }
        pairs += static_cast<double>((box.i1 / B - box.i0 / B + 1)) * (box.j1 / B - box.j0 / B + 1) *
                 (box.k1 / B - box.k0 / B + 1);
    }
    if (pairs > static_cast<double>(def.max_ball_blocks)) {
        return Error{"sparse field: " + std::to_string(pairs) + " (ball, block) pairs, more than the cap " +
                     std::to_string(def.max_ball_blocks) + " (kernel radius too large for the spacing?)"};
    }

    return pairs;
}

size_t SparseField::bin_balls(size_t nblocks) {
    // 2. Counting sort: count, prefix sum, fill in ball order.
    const auto for_blocks = [&](const BallBox& box, auto&& f) {
        for (int bk = box.k0 / B; bk <= box.k1 / B; ++bk)
            for (int bj = box.j0 / B; bj <= box.j1 / B; ++bj) {
                const size_t row = block_index(0, bj, bk);
                for (int bi = box.i0 / B; bi <= box.i1 / B; ++bi) f(row + static_cast<size_t>(bi));
            }
    };
    list_start_.resize(nblocks + 1);
    std::fill(list_start_.begin(), list_start_.end(), 0u);
    for (const BallBox& box : boxes_) {
        if (box.i0 > box.i1) continue;
        for_blocks(box, [&](size_t blk) { ++list_start_[blk + 1]; });
    }
    // 3. Prefix sum and slots for non-empty blocks, in block order.
    block_of_slot_.resize(nblocks);
    size_t slots = 0;
    for (size_t blk = 0; blk < nblocks; ++blk) {
        if (list_start_[blk + 1] != 0) {
            directory_[blk] = static_cast<int32_t>(slots);
            block_of_slot_[slots++] = static_cast<uint32_t>(blk);
        }
        list_start_[blk + 1] += list_start_[blk];
    }
    list_fill_.assign(list_start_.begin(), list_start_.end() - 1);
    if (lists_.size() < stats_.ball_blocks) lists_.resize(stats_.ball_blocks);
    for (size_t b = 0; b < boxes_.size(); ++b) {
        if (boxes_[b].i0 > boxes_[b].i1) continue;
        for_blocks(boxes_[b], [&](size_t blk) { lists_[list_fill_[blk]++] = static_cast<uint32_t>(b); });
    }
    allocated_ = slots;
    stats_.allocated_blocks = slots;
    if (pool_.size() < slots * kBlockSamples) pool_.resize(slots * kBlockSamples);
    if (block_min_.size() < slots) {
        block_min_.resize(slots);
        block_max_.resize(slots);
    }
    return slots;
}

void SparseField::splat_blocks(std::span<const Vec3> balls, const KernelDef& kdef, size_t slots) {
    const float radius = kdef.radius;
    const float sup2 = radius * radius;
    // 4. Per-block gather, in parallel; each task writes only its own block.
    const auto t1 = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, slots), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t s = r.begin(); s != r.end(); ++s) {
            const size_t blk = block_of_slot_[s];
            const auto [bi, bj, bk] = block_coords(blk, bx_, by_);
            const int i0 = bi * B, j0 = bj * B, k0 = bk * B;
            float* out = pool_.data() + s * kBlockSamples;
            const uint32_t* list = lists_.data() + list_start_[blk];
            const size_t count = list_start_[blk + 1] - list_start_[blk];
            const auto run = [&](auto kernel) {
#if defined(METARIVER_FIELD_AVX2)
                if (avx2_enabled()) {
                    splat_block_avx2(grid_, balls.data(), list, count, boxes_.data(), sup2, kernel, i0, j0, k0, out);
                    return;
                }
#endif
                splat_block(grid_, balls.data(), list, count, boxes_.data(), sup2, kernel, i0, j0, k0, out);
            };
            if (kdef.type == FieldKernel::W1) {
                run(W1Eval{kdef.strength, kdef.subtract});
            } else {
                run(Poly6Eval{kdef.amplitude, 1.0f / (radius * radius)});
            }
            // Lanes past the grid's last column hold kernel values of absent samples: zero them.
            const int lx = grid_.nx - i0;
            if (lx < B) {
                for (int row = 0; row < B * B; ++row) std::fill(out + B * row + lx, out + B * row + B, 0.0f);
            }
            block_range(out, block_min_[s], block_max_[s]);
        }
    });
    stats_.ms_splat = ms_since(t1);
}

void SparseField::add_level_term(const LevelAt& level, float amplitude, float width) {
    add_level_columns([&](int, int, float x, float z, float& s) { return level(x, z, s); }, amplitude, width);
}

void SparseField::add_level_term(std::span<const float> column_level, float amplitude, float width) {
    const size_t nx = size_t(std::max(grid_.nx, 0));
    if (column_level.size() < nx * size_t(std::max(grid_.nz, 0))) return;
    add_level_columns(
        [&](int i, int k, float, float, float& s) {
            s = column_level[size_t(i) + nx * size_t(k)];
            return !std::isnan(s);
        },
        amplitude, width);
}

template <class Level>
void SparseField::add_level_columns(const Level& level, float amplitude, float width) {
    if (!(width > 0.0f) || allocated_ == 0) return;
    const float inv_width = 1.0f / width, h = grid_.spacing;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, allocated_), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t s = r.begin(); s != r.end(); ++s) {
            const size_t blk = block_of_slot_[s];
            const auto [bi, bj, bk] = block_coords(blk, bx_, by_);
            float* out = pool_.data() + s * kBlockSamples;
            const int nx = std::min(B, grid_.nx - bi * B), ny = std::min(B, grid_.ny - bj * B),
                      nz = std::min(B, grid_.nz - bk * B);
            for (int z = 0; z < nz; ++z)
                for (int x = 0; x < nx; ++x) {
                    const Vec3 p = grid_.position(bi * B + x, bj * B, bk * B + z);
                    float lv = 0.0f;
                    if (!level(bi * B + x, bk * B + z, p.x, p.z, lv)) continue;
                    for (int y = 0; y < ny; ++y) {
                        const float sy = grid_.origin.y + h * static_cast<float>(bj * B + y);
                        out[x + B * (y + B * z)] += amplitude * std::clamp(1.0f + (lv - sy) * inv_width, 0.0f, 2.0f);
                    }
                }
            block_range(out, block_min_[s], block_max_[s]);
        }
    });
}

Status SparseField::from_dense(const ScalarGrid& d) {
    const auto t0 = std::chrono::steady_clock::now();
    clear_grid();
    stats_ = SparseFieldStats{};
    if (d.nx < 0 || d.ny < 0 || d.nz < 0 || d.values.size() < d.size()) {
        return Error{"sparse field: the dense grid holds fewer values than nx * ny * nz"};
    }
    grid_ = SampleGrid{.origin = d.origin, .spacing = d.spacing, .nx = d.nx, .ny = d.ny, .nz = d.nz};
    bx_ = (d.nx + B - 1) / B;
    by_ = (d.ny + B - 1) / B;
    bz_ = (d.nz + B - 1) / B;
    const size_t nblocks = block_count();
    directory_.resize(nblocks);
    std::fill(directory_.begin(), directory_.end(), kNoBlock);
    stats_.blocks = nblocks;
    const auto block_extent = [&](int b, int n) { return std::min(B, n - b * B); };
    // Which blocks hold anything but 0, then copy them into slots in block order.
    size_t slots = 0;
    for (int bk = 0; bk < bz_; ++bk)
        for (int bj = 0; bj < by_; ++bj)
            for (int bi = 0; bi < bx_; ++bi) {
                bool used = false;
                for (int k = 0; k < block_extent(bk, d.nz) && !used; ++k)
                    for (int j = 0; j < block_extent(bj, d.ny) && !used; ++j) {
                        const float* row = d.values.data() + d.index(bi * B, bj * B + j, bk * B + k);
                        for (int i = 0; i < block_extent(bi, d.nx); ++i) used = used || !(row[i] == 0.0f);
                    }
                if (used) directory_[block_index(bi, bj, bk)] = static_cast<int32_t>(slots++);
            }
    allocated_ = slots;
    stats_.allocated_blocks = slots;
    if (pool_.size() < slots * kBlockSamples) pool_.resize(slots * kBlockSamples);
    if (block_min_.size() < slots) {
        block_min_.resize(slots);
        block_max_.resize(slots);
    }
    if (block_of_slot_.size() < slots) block_of_slot_.resize(slots);
    for (int bk = 0; bk < bz_; ++bk)
        for (int bj = 0; bj < by_; ++bj)
            for (int bi = 0; bi < bx_; ++bi) {
                const int32_t s = directory_[block_index(bi, bj, bk)];
                if (s == kNoBlock) continue;
                block_of_slot_[static_cast<size_t>(s)] = static_cast<uint32_t>(block_index(bi, bj, bk));
                float* out = pool_.data() + static_cast<size_t>(s) * kBlockSamples;
                std::fill(out, out + kBlockSamples, 0.0f);
                for (int k = 0; k < block_extent(bk, d.nz); ++k)
                    for (int j = 0; j < block_extent(bj, d.ny); ++j) {
                        const float* row = d.values.data() + d.index(bi * B, bj * B + j, bk * B + k);
                        std::copy(row, row + block_extent(bi, d.nx), out + B * (j + B * k));
                    }
                float lo = std::numeric_limits<float>::infinity(), hi = -lo;
                bool nan = false;
                for (int n = 0; n < kBlockSamples; ++n) {
                    if (std::isnan(out[n])) {
                        nan = true;
                        continue;
                    }
                    lo = std::min(lo, out[n]);
                    hi = std::max(hi, out[n]);
                }
                block_min_[s] = nan ? -std::numeric_limits<float>::infinity() : lo;
                block_max_[s] = hi;
            }
    stats_.ms_bin = ms_since(t0);
    return Ok{};
}

float SparseField::value(int i, int j, int k) const {
    const int32_t s = slot(i / B, j / B, k / B);
    if (s == kNoBlock) return 0.0f;
    return block_values(s)[(i % B) + B * ((j % B) + B * (k % B))];
}

void SparseField::to_dense(ScalarGrid& out) const {
    out.reset(grid_.nx, grid_.ny, grid_.nz, grid_.origin, grid_.spacing, 0.0f);
    for (int bk = 0; bk < bz_; ++bk)
        for (int bj = 0; bj < by_; ++bj)
            for (int bi = 0; bi < bx_; ++bi) {
                const int32_t s = slot(bi, bj, bk);
                if (s == kNoBlock) continue;
                const float* v = block_values(s);
                const int lx = std::min(B, grid_.nx - bi * B);
                for (int k = 0; k < B && bk * B + k < grid_.nz; ++k)
                    for (int j = 0; j < B && bj * B + j < grid_.ny; ++j) {
                        const float* row = v + B * (j + B * k);
                        std::copy(row, row + lx, out.values.data() + out.index(bi * B, bj * B + j, bk * B + k));
                    }
            }
}

size_t SparseField::capacity_bytes() const {
    return directory_.capacity() * sizeof(int32_t) + pool_.capacity() * sizeof(float) +
           (block_min_.capacity() + block_max_.capacity()) * sizeof(float) +
           block_of_slot_.capacity() * sizeof(uint32_t) + boxes_.capacity() * sizeof(BallBox) +
           (list_start_.capacity() + list_fill_.capacity() + lists_.capacity()) * sizeof(uint32_t);
}

}  // namespace mr
