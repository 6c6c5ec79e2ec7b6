// metariver field: compact-support kernels splatted into a sparse block grid.
//
// The paper's field (field.h) lets every ball touch every sample: O(balls x samples).
// Here each ball's kernel is exactly zero beyond a support radius, so a ball only
// touches the samples inside its support, and the grid is stored as blocks of 8^3
// samples that exist only where some ball reaches: empty space costs one directory
// entry per block. The build is a gather (each block sums its own balls, in ball
// order), so it needs no atomics and gives bitwise identical values for any thread
// count. Kernels: the peers' W1 kernel (three.js MarchingCubes' addBall, see
// ../shared/peers/README.md) and Wyvill's (1 - r^2/R^2)^3 ("poly6",
// Mueller et al. 2003) for the simulation.
#pragma once

#include <metariver/core.h>
#include <metariver/field.h>

#include <cstdint>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

namespace mr {

/// A radially symmetric kernel that is exactly 0 at distances >= radius (its support).
/// Build one with w1_kernel() or poly6_kernel(), which fill the fields consistently.
struct KernelDef {
    /// Poly6: amplitude * (1 - r^2 / radius^2)^3 (Wyvill / poly6), smooth, C1 at the
    /// support; W1: max(0, strength / (r^2 + 1e-6 m^2) - subtract). The dense kernels are
    /// not compact: validate() refuses them.
    FieldKernel type = FieldKernel::Poly6;
    float radius = 1.0f;     ///< support radius, metres, > 0: the kernel is 0 where r >= radius
    float amplitude = 1.0f;  ///< Poly6: value at the centre, field units (any finite value)
    float strength = 0.0f;   ///< W1: S, field units x m^2, > 0
    float subtract = 0.0f;   ///< W1: SUB, field units, > 0
};

/// W1 kernel with support sqrt(strength / subtract) metres (where S/r^2 - SUB reaches 0).
KernelDef w1_kernel(float strength, float subtract);
/// Poly6 kernel: `amplitude` at the centre, 0 from `radius` metres on.
KernelDef poly6_kernel(float radius, float amplitude);
/// The kernel's value at squared distance r2 (m^2); the reference the fast loops follow.
float kernel_value(const KernelDef& k, float r2);
/// Error when the kernel is not a compact one (Poly6, W1) or its fields are out of range
/// (non-finite, radius <= 0, W1 with S or SUB <= 0).
Status validate(const KernelDef& k);

/// The paper's domain rule (as compute_field_paper): the balls' bounding box grown by
/// `offset` metres on every side, `resolution` samples per metre, samples per axis =
/// ceil(extent * resolution) + 1. No balls: an empty grid at the origin. Error when the
/// grid would exceed max_samples, or on non-finite input or resolution <= 0.
Result<SampleGrid> grid_around(std::span<const Vec3> balls, float resolution, float offset,
                               size_t max_samples = kMaxFieldSamples);

/// Where the sparse field's samples lie.
enum class DomainMode {
    BallBounds,  ///< grid_around(balls, resolution, bounds_offset) each build
    FixedBox,    ///< `box`, whatever the balls (balls outside add only where they reach in)
};

/// The sparse field's cap on its grid's dense sample count: the directory holds one
/// 4-byte slot per 8^3 block (2^23 blocks, 32 MiB, at this cap) and block indices are
/// 32-bit. Far above kMaxFieldSamples (the dense field's, which stores every sample): a
/// river along a 1.5 km channel spans 2181 x 96 x 1404 samples (random_1000x700), of which
/// it stores a few thousand blocks.
inline constexpr size_t kMaxSparseFieldSamples = size_t{1} << 32;

/// Keeps the balls whose field fits the cap. When grid_around(balls, resolution, offset)
/// would have more than max_samples samples (particles spread over kilometres), keeps only
/// the balls inside the largest cube whose grid fits (0.9 of it), centred on the mean of
/// the balls in the cell, of a grid of half that side, that holds the most of them; the
/// others are erased (the rest keep their order). Returns how many were left out: 0 when
/// all fit, or when not even one ball's grid does (nothing erased).
size_t keep_balls_within_cap(std::vector<Vec3>& balls, float resolution, float offset,
                             size_t max_samples = kMaxSparseFieldSamples);

struct SparseFieldDef {
    KernelDef kernel;
    DomainMode domain = DomainMode::BallBounds;
    float resolution = 2.0f;     ///< BallBounds: samples per metre, > 0
    float bounds_offset = 4.0f;  ///< BallBounds: metres the balls' box grows by on every side, >= 0
    SampleGrid box;              ///< FixedBox: the grid
    size_t max_samples = kMaxSparseFieldSamples;  ///< refuse grids with more samples (dense count)
    /// Refuse a build whose (ball, block) pairs exceed this: bounds the binning memory
    /// (4 bytes each) when balls are huge compared with the spacing.
    size_t max_ball_blocks = size_t{1} << 26;
};

/// Numbers from the last build, for tests and the bench.
struct SparseFieldStats {
    size_t balls = 0;             ///< balls splatted
    size_t blocks = 0;            ///< blocks in the directory (allocated or not)
    size_t allocated_blocks = 0;  ///< blocks some ball reaches
    size_t ball_blocks = 0;       ///< (ball, block) pairs binned
    double ms_bin = 0.0;          ///< bounds, binning, slot allocation (serial)
    double ms_splat = 0.0;        ///< parallel per-block sums and min/max
};

/// A scalar field on a SampleGrid stored as blocks of kBlock^3 samples. Block (bi, bj, bk)
/// holds samples [8 bi, 8 bi + 8) x ... ; blocks no ball reaches are not stored and read
/// as 0. Storage is reused across builds (it grows to the largest frame, never shrinks),
/// so a build of a same-sized frame allocates nothing.
class SparseField {
public:
    static constexpr int kBlock = 8;                                    ///< samples per block edge
    static constexpr int kBlockSamples = kBlock * kBlock * kBlock;      ///< 512
    static constexpr int32_t kNoBlock = -1;                             ///< directory: not stored

    /// Sums the kernel of every ball into the samples within its support. On error the
    /// field is left empty (0 samples) and nothing huge was allocated.
    Status build(std::span<const Vec3> balls, const SparseFieldDef& def);
    /// Copies a dense grid, storing the blocks that hold a non-zero (or NaN) sample. For
    /// tests and for fields made elsewhere. Error (field left empty) when the grid holds
    /// fewer values than its size says. A NaN sample makes its block's min -inf (NaN
    /// counts as outside, below any threshold).
    Status from_dense(const ScalarGrid& grid);

    const SampleGrid& grid() const { return grid_; }
    int blocks_x() const { return bx_; }
    int blocks_y() const { return by_; }
    int blocks_z() const { return bz_; }
    size_t block_count() const { return static_cast<size_t>(bx_) * by_ * bz_; }
    size_t block_index(int bi, int bj, int bk) const {
        return static_cast<size_t>(bi) + static_cast<size_t>(bx_) * (static_cast<size_t>(bj) + static_cast<size_t>(by_) * bk);
    }
    /// Slot of block (bi, bj, bk) in the storage, or kNoBlock; the block must be in range.
    int32_t slot(int bi, int bj, int bk) const { return directory_[block_index(bi, bj, bk)]; }
    /// The directory: one slot (or kNoBlock) per block, block_index order.
    std::span<const int32_t> directory() const { return {directory_.data(), block_count()}; }
    size_t allocated_blocks() const { return allocated_; }
    /// A stored block's samples, x fastest: [x + 8 (y + 8 z)]. Samples beyond the grid's
    /// last row/column/layer (partial edge blocks) are 0.
    const float* block_values(int32_t slot) const { return pool_.data() + static_cast<size_t>(slot) * kBlockSamples; }
    /// Smallest and largest sample of a stored block (over all 512, so a partial block's
    /// padding 0s count: a safe bound for the in-grid samples).
    float block_min(int32_t slot) const { return block_min_[static_cast<size_t>(slot)]; }
    float block_max(int32_t slot) const { return block_max_[static_cast<size_t>(slot)]; }

    /// Where a level: for a column (x, z) of samples, the height of a surface there
    /// (true), or false (no term in that column). Called from several threads at once.
    using LevelAt = std::function<bool(float x, float z, float& level)>;
    /// Adds a water surface's term to the stored blocks (those no ball reaches stay
    /// absent, 0): in each column (x, z) whose `level` gives s, a sample at height y gets
    /// amplitude * clamp(1 + (s - y) / width, 0, 2): `amplitude` at s, 0 from `width`
    /// above, twice it from `width` below. Linear in y between, so marching cubes puts
    /// the iso surface (threshold = amplitude) of the term alone exactly at s on vertical
    /// edges, and where balls add, it rises smoothly around them (issue 46's seam,
    /// join_heightfield_to_field in surface.h). Updates the blocks' min and max.
    void add_level_term(const LevelAt& level, float amplitude, float width);
    /// The same term from one level per column of samples, `column_level[i + nx * k]`
    /// (NaN: no term in that column; at least nx * nz values, else nothing is added): what
    /// add_level_term(level) adds where level(x, z) gives those values at the columns'
    /// (x, z). It reads a table instead of calling a function per column and block.
    void add_level_term(std::span<const float> column_level, float amplitude, float width);

    /// Sample (i, j, k), 0 <= i < nx...; 0 where no ball reaches.
    float value(int i, int j, int k) const;
    /// The same samples as a dense grid (for tests and the serial extractor).
    void to_dense(ScalarGrid& out) const;

    const SparseFieldStats& stats() const { return stats_; }
    /// Bytes of reserved storage (capacities), to check that steady-state frames do not grow it.
    size_t capacity_bytes() const;

private:
    void clear_grid();
    /// add_level_term's loop over the stored blocks; level(i, k, x, z, s) gives column (i, k)'s.
    template <class Level>
    void add_level_columns(const Level& level, float amplitude, float width);
    // build()'s stages: the sample grid (around the balls or the fixed box, checked), each
    // ball's sample box and the (ball, block) pair count (checked against the cap), the
    // counting sort of balls by block (returns the non-empty blocks' slot count), and the
    // per-block gather.
    Result<SampleGrid> build_grid(std::span<const Vec3> balls, const SparseFieldDef& def) const;
    Result<double> ball_boxes(std::span<const Vec3> balls, const SampleGrid& g, const SparseFieldDef& def);
    size_t bin_balls(size_t nblocks);
    void splat_blocks(std::span<const Vec3> balls, const KernelDef& kdef, size_t slots);

    SampleGrid grid_;
    int bx_ = 0, by_ = 0, bz_ = 0;
    size_t allocated_ = 0;
    SparseFieldStats stats_;
    // Block directory: dense over the domain (4 bytes per 512 samples), so any block is
    // found with one multiply-add; slots index the pool in block order.
    std::vector<int32_t> directory_;
    std::vector<float> pool_;  // allocated_ * 512 values used; size never shrinks
    std::vector<float> block_min_, block_max_;
    std::vector<uint32_t> block_of_slot_;  // directory index of each slot
    // Binning (counting sort of balls by block): per-ball sample boxes, per-block counts
    // turned into list starts, and the ball lists themselves (ascending ball index).
    struct BallBox {
        int i0, i1, j0, j1, k0, k1;  // inclusive sample ranges, clipped to the grid
    };
    std::vector<BallBox> boxes_;
    std::vector<uint32_t> list_start_;  // per block, + 1: start of its ball list
    std::vector<uint32_t> list_fill_;   // per block: fill cursor
    std::vector<uint32_t> lists_;
};

// ---- The W1 workload of ../shared/peers/README.md (shared by tests and benches) ----

/// W1 balls: for each ball x, y, z = 0.1 + 0.8 * next() of the pinned LCG (in that
/// order), computed in double and rounded to float. Ball 0 for seed 12345 is
/// (0.116322149, 0.113238279, 0.534524636).
std::vector<Vec3> w1_balls(int n, uint32_t seed = 12345u);
/// W1 kernel for n balls: r = rcoef * n^(-1/3), S = (iso + sub) r^2, SUB = sub,
/// support r * sqrt((iso + sub) / sub).
KernelDef w1_kernel_for(int n, float rcoef = 0.3f, float iso = 80.0f, float sub = 12.0f);
/// W1 grid: res samples per axis over the closed unit cube (spacing 1 / (res - 1)).
SampleGrid w1_grid(int res);
/// W1's iso value.
inline constexpr float kW1Iso = 80.0f;

}  // namespace mr
