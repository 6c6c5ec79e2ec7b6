// metariver surface: block-parallel marching cubes on a SparseField.
//
// Paul Bourke, "Polygonising a scalar field" (1994): the cases and tables (mc_tables.cpp).
// Two passes over blocks of 8^3 samples, in the manner of Flying Edges (Schroeder,
// Maynard, Geveci, "Flying edges: a high-performance scalable isocontouring algorithm",
// IEEE LDAV 2015): count first, then write every vertex and triangle straight to its
// final place, so no locks, no atomics and no merging.
//
// Ownership: a block owns the grid edges whose lower sample lies in it (x, y and z edges)
// and the cells whose lower corner lies in it. A cell on the block's +x/+y/+z faces uses
// edges owned by the +x, +y, +z, +xy, +xz or +yz neighbour.
//
//   select    Candidate blocks: the value range of the block and its 7 +x/+y/+z
//             neighbours (block min/max; an absent block is all 0) straddles the threshold.
//             Other blocks own no crossed edge and no cut cell.
//   classify  (parallel) Per candidate: the inside bits of samples [0, 8]^3 (9 bits per
//             row); from them, 8 rows at a time in 64-bit words, the crossed owned edges
//             as one byte per (row, direction) and each row's rank (edges before it);
//             the triangles of owned cells, visiting only cells with mixed corners.
//   offsets   Prefix sums over candidates in block order: each block's first vertex and
//             first triangle. The mesh is resized once.
//   emit      (parallel) Vertices of owned crossed edges, at first vertex + rank; the
//             samples [-1, 9]^3 around the block are gathered first so the gradient uses
//             the same neighbours (one-sided at the grid border) as extract_surface.
//             Triangles of owned cells: an edge of this block by its local index
//             (recorded while emitting), an edge on the +x/+y/+z faces as the owner's
//             first vertex + rank of the edge in the owner's bits: the same vertex from
//             both sides of a block seam, so vertices stay welded across blocks.
// The vertex arithmetic (interpolation, gradient, normal) is extract_surface's, expression
// for expression, so positions and normals agree bit for bit (marching_cubes_sparse_test
// checks it). Output order depends only on the field, not on the threads.
#include <metariver/surface.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mr {

namespace {

constexpr int B = SparseField::kBlock;
constexpr int P = B + 3;  // padded block edge: samples -1 .. 9

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

inline bool is_inside(float v, float threshold) { return v > threshold; }  // NaN: outside

/// Cell corners as read from four rows of inside bits: key bit 2r + d is row r's bit at
/// x + d, rows r = m00 (y, z), m01 (y, z + 1), m10 (y + 1, z), m11 (y + 1, z + 1).
/// In Bourke's numbering those are corners 0, 1, 3, 2, 4, 5, 7, 6.
constexpr std::array<int, 8> kKeyCorner = {0, 1, 3, 2, 4, 5, 7, 6};

/// A triangle corner's edge seen from its cell: one of the 8 edge rows around a cell row
/// (0-3: x edges at (y + dy, z + dz), slot dy + 2 dz; 4-5: y edges at (y, z + dz);
/// 6-7: z edges at (y + dy, z)) and the x offset (0 or 1) in that row.
struct EdgeRef {
    uint8_t row;
    uint8_t dx;
};

struct Tables {
    std::array<uint8_t, 256> cube_of_key{};        // key -> Bourke cube index
    std::array<uint8_t, 256> triangles_of_key{};   // triangles of each key
    std::array<uint16_t, 256> edges_of_key{};      // crossed Bourke edges of each key
    std::array<std::array<uint8_t, 8>, 256> below{};  // [b][x]: bits of b below bit x
    std::array<EdgeRef, 12> edge_ref{};            // Bourke edge -> edge row and x offset
    std::array<uint16_t, 12> local_offset{};       // Bourke edge -> offset in local_id from the cell's
};

Tables make_tables() {
    Tables t;
    for (int e = 0; e < 12; ++e) {
        const auto& a = mc::kCornerOffset[mc::kEdgeCorners[e][0]];
        const auto& b = mc::kCornerOffset[mc::kEdgeCorners[e][1]];
        int axis = 0;
        for (int d = 0; d < 3; ++d) {
            if (a[d] != b[d]) axis = d;
        }
        const int dx = std::min(a[0], b[0]), dy = std::min(a[1], b[1]), dz = std::min(a[2], b[2]);
        const int row = axis == 0 ? dy + 2 * dz : axis == 1 ? 4 + dz : 6 + dy;
        t.edge_ref[e] = EdgeRef{static_cast<uint8_t>(row), static_cast<uint8_t>(dx)};
        t.local_offset[e] = static_cast<uint16_t>(axis * B * B * B + dx + B * (dy + B * dz));
    }
    for (int key = 0; key < 256; ++key) {
        int cube = 0;
        for (int b = 0; b < 8; ++b) cube |= ((key >> b) & 1) << kKeyCorner[b];
        t.cube_of_key[key] = static_cast<uint8_t>(cube);
        int n = 0;
        while (n < 16 && mc::kTriTable[cube][n] >= 0) ++n;
        t.triangles_of_key[key] = static_cast<uint8_t>(n / 3);
        t.edges_of_key[key] = mc::kEdgeTable[cube];
        int bits = 0;
        for (int b = 0; b < 8; ++b) {
            t.below[key][b] = static_cast<uint8_t>(bits);
            bits += (key >> b) & 1;
        }
    }
    return t;
}

const Tables& tables() {
    static const Tables t = make_tables();
    return t;
}

/// The four sample rows of a cell row, packed 16 bits apart for key extraction.
inline uint64_t pack_rows(unsigned m00, unsigned m01, unsigned m10, unsigned m11) {
    return uint64_t{m00} | (uint64_t{m01} << 16) | (uint64_t{m10} << 32) | (uint64_t{m11} << 48);
}

/// Key of cell x of a packed cell row (see kKeyCorner).
inline unsigned cell_key(uint64_t rows, int x) {
    uint64_t v = (rows >> x) & 0x0003000300030003ull;
    v |= v >> 14;  // row 1's pair to bits 2-3, row 3's to bits 34-35
    v |= v >> 28;  // rows 2-3 to bits 4-7
    return static_cast<unsigned>(v & 0xffu);
}

/// Cells of a row (bit x, x < ex) whose 8 corners are not all on one side.
inline unsigned mixed_cells(unsigned m00, unsigned m01, unsigned m10, unsigned m11, unsigned cell_mask) {
    const unsigned e = (m00 ^ m01) | (m00 ^ m10) | (m00 ^ m11);
    return (e | (e >> 1) | (m00 ^ (m00 >> 1))) & cell_mask;
}

/// Pass-1 results of one candidate block. Rows are indexed y + 8 z (edges) or
/// y + 9 z (inside bits, which include the neighbours' first layer), bit x.
struct BlockCells {
    uint16_t inside[81];    // inside bits of samples x, y, z in [0, 8]
    uint8_t edges[3][64];   // crossed owned edges along x, y, z whose lower sample is (x, y, z)
    uint16_t word_base[3][8];  // block-local vertex index of the first edge in layer z
    uint8_t prefix[3][64];     // crossed edges before row y in layer z (rank = word_base + prefix)
    uint32_t vertices;      // owned crossed edges (x first, then y, then z)
    uint32_t triangles;     // triangles of owned cells
    uint32_t block;         // directory index
    uint32_t first_vertex;  // global index of the block's first vertex
    uint32_t first_triangle;
    int16_t ex, ey, ez;     // cells (= edges along that axis) per axis in this block: 0..8
    int16_t lx, ly, lz;     // samples per axis in this block: 1..8
};

}  // namespace

struct SurfaceWorkspace::Impl {
    std::vector<int32_t> candidate_of_block;  // per directory block: index in cells, or -1
    std::vector<uint32_t> candidates;         // directory index of each candidate, block order
    std::vector<BlockCells> cells;            // pass-1 record of each candidate (size >= candidates)
};

SurfaceWorkspace::SurfaceWorkspace() : impl(std::make_unique<Impl>()) {}
SurfaceWorkspace::~SurfaceWorkspace() = default;
SurfaceWorkspace::SurfaceWorkspace(SurfaceWorkspace&&) noexcept = default;
SurfaceWorkspace& SurfaceWorkspace::operator=(SurfaceWorkspace&&) noexcept = default;

size_t SurfaceWorkspace::capacity_bytes() const {
    if (!impl) return 0;
    return impl->candidate_of_block.capacity() * sizeof(int32_t) + impl->candidates.capacity() * sizeof(uint32_t) +
           impl->cells.capacity() * sizeof(BlockCells);
}

namespace {

/// Everything the passes read, bundled once per call.
struct Context {
    const SparseField* field;
    const SampleGrid* grid;
    float threshold;
    unsigned outside_bits;  // inside bits of an absent block's row (0 < threshold: none)
    const int32_t* candidate_of_block;
    BlockCells* cells;
    SurfaceMesh* out;

    /// Values of block (bi, bj, bk), or nullptr when it is outside the grid or not stored.
    const float* block(int bi, int bj, int bk) const {
        if (bi >= field->blocks_x() || bj >= field->blocks_y() || bk >= field->blocks_z()) return nullptr;
        if (bi < 0 || bj < 0 || bk < 0) return nullptr;
        const int32_t s = field->slot(bi, bj, bk);
        return s == SparseField::kNoBlock ? nullptr : field->block_values(s);
    }
    void block_coords(uint32_t blk, int& bi, int& bj, int& bk) const {
        const auto bx = static_cast<uint32_t>(field->blocks_x()), by = static_cast<uint32_t>(field->blocks_y());
        bi = static_cast<int>(blk % bx);
        bj = static_cast<int>((blk / bx) % by);
        bk = static_cast<int>(blk / (bx * by));
    }
};

/// Inside bits of 8 consecutive samples.
inline unsigned row_bits(const float* v, float threshold) {
#if defined(__SSE2__)
    const __m128 t = _mm_set1_ps(threshold);  // ordered compare: NaN is outside, as is_inside
    return static_cast<unsigned>(_mm_movemask_ps(_mm_cmpgt_ps(_mm_loadu_ps(v), t))) |
           (static_cast<unsigned>(_mm_movemask_ps(_mm_cmpgt_ps(_mm_loadu_ps(v + 4), t))) << 4);
#else
    unsigned m = 0;
    for (int i = 0; i < B; ++i) m |= static_cast<unsigned>(is_inside(v[i], threshold)) << i;
    return m;
#endif
}

/// Pass 1 for one candidate.
void classify(const Context& cx, BlockCells& bc) {
    const Tables& tb = tables();
    const float t = cx.threshold;
    int bi, bj, bk;
    cx.block_coords(bc.block, bi, bj, bk);
    const SampleGrid& g = *cx.grid;
    bc.lx = static_cast<int16_t>(std::min(B, g.nx - bi * B));
    bc.ly = static_cast<int16_t>(std::min(B, g.ny - bj * B));
    bc.lz = static_cast<int16_t>(std::min(B, g.nz - bk * B));
    bc.ex = static_cast<int16_t>(std::min(B, g.nx - 1 - bi * B));
    bc.ey = static_cast<int16_t>(std::min(B, g.ny - 1 - bj * B));
    bc.ez = static_cast<int16_t>(std::min(B, g.nz - 1 - bk * B));

    // Inside bits of samples [0, 8]^3: the block's own 8^3 and the first layer of the
    // +x, +y, +z, +xy, +xz, +yz, +xyz neighbours. Absent samples give outside_bits; bits
    // of samples beyond the grid are never used (the e* / l* limits below).
    const float* own = cx.block(bi, bj, bk);
    const float* nbx = cx.block(bi + 1, bj, bk);
    const float* nby = cx.block(bi, bj + 1, bk);
    const float* nbz = cx.block(bi, bj, bk + 1);
    const float* nxy = cx.block(bi + 1, bj + 1, bk);
    const float* nxz = cx.block(bi + 1, bj, bk + 1);
    const float* nyz = cx.block(bi, bj + 1, bk + 1);
    const float* nxyz = cx.block(bi + 1, bj + 1, bk + 1);
    const unsigned out8 = cx.outside_bits & 0xffu, out1 = cx.outside_bits & 1u;
    const auto bit = [&](const float* blk, int x, int y, int z) {
        return blk ? static_cast<unsigned>(is_inside(blk[x + B * (y + B * z)], t)) : out1;
    };
    // Also as 64-bit words, 8 rows (y = 0..7) of 8 bits per layer z = 0..8 (x8: the
    // rows' bit 8 in bit 0 of each byte; y8: row y = 8), to find crossed edges for 8
    // rows at a time.
    uint64_t xw[9], x8[9];
    unsigned y8[9];
    const auto put_row = [&](int y, int z, unsigned lo, unsigned hi) {
        bc.inside[y + 9 * z] = static_cast<uint16_t>(lo | (hi << 8));
        if (y < B) {
            xw[z] |= uint64_t{lo} << (8 * y);
            x8[z] |= uint64_t{hi} << (8 * y);
        } else {
            y8[z] = lo;
        }
    };
    for (int z = 0; z <= B; ++z) xw[z] = x8[z] = 0;
    for (int z = 0; z < B; ++z) {
        for (int y = 0; y < B; ++y) put_row(y, z, own ? row_bits(own + B * (y + B * z), t) : out8, bit(nbx, 0, y, z));
        put_row(B, z, nby ? row_bits(nby + B * (0 + B * z), t) : out8, bit(nxy, 0, 0, z));
    }
    for (int y = 0; y < B; ++y) put_row(y, B, nbz ? row_bits(nbz + B * y, t) : out8, bit(nxz, 0, y, 0));
    put_row(B, B, nyz ? row_bits(nyz, t) : out8, bit(nxyz, 0, 0, 0));

    // Crossed owned edges (bytes: row y of layer z) and their ranks: x edges, then y,
    // then z; only edges whose samples are both in the grid.
    constexpr uint64_t kBytes = 0x0101010101010101ull;
    const auto rows_below = [](int n) { return n >= B ? ~uint64_t{0} : (uint64_t{1} << (8 * n)) - 1; };
    const uint64_t xmask = kBytes * ((1u << bc.ex) - 1u) & rows_below(bc.ly);  // x edges
    const uint64_t ymask = kBytes * ((1u << bc.lx) - 1u) & rows_below(bc.ey);  // y edges
    const uint64_t zmask = kBytes * ((1u << bc.lx) - 1u) & rows_below(bc.ly);  // z edges
    uint32_t n = 0;
    for (int axis = 0; axis < 3; ++axis) {
        for (int z = 0; z < B; ++z) {
            const uint64_t m = xw[z];
            uint64_t e = 0;
            if (axis == 0 && z < bc.lz) {
                e = (m ^ (((m >> 1) & (kBytes * 0x7fu)) | (x8[z] << 7))) & xmask;
            } else if (axis == 1 && z < bc.lz) {
                e = (m ^ ((m >> 8) | (uint64_t{y8[z]} << 56))) & ymask;
            } else if (axis == 2 && z < bc.ez) {
                e = (m ^ xw[z + 1]) & zmask;
            }
            // Bits per byte, then running sums over the bytes (each <= 64: no carries).
            uint64_t c = e - ((e >> 1) & (kBytes * 0x55u));
            c = (c & (kBytes * 0x33u)) + ((c >> 2) & (kBytes * 0x33u));
            c = (c + (c >> 4)) & (kBytes * 0x0fu);
            const uint64_t running = c * kBytes;  // byte y: bits in bytes 0..y
            for (int y = 0; y < B; ++y) {
                bc.edges[axis][y + B * z] = static_cast<uint8_t>(e >> (8 * y));
                bc.prefix[axis][y + B * z] = static_cast<uint8_t>((running << 8) >> (8 * y));
            }
            bc.word_base[axis][z] = static_cast<uint16_t>(n);
            n += static_cast<uint32_t>(running >> 56);
        }
    }
    bc.vertices = n;

    // Triangles of owned cells, visiting only cells with corners on both sides.
    const unsigned cell_mask = (1u << bc.ex) - 1u;
    uint32_t tris = 0;
    for (int z = 0; z < bc.ez; ++z) {
        for (int y = 0; y < bc.ey; ++y) {
            const unsigned m00 = bc.inside[y + 9 * z], m10 = bc.inside[y + 1 + 9 * z];
            const unsigned m01 = bc.inside[y + 9 * (z + 1)], m11 = bc.inside[y + 1 + 9 * (z + 1)];
            unsigned mixed = mixed_cells(m00, m01, m10, m11, cell_mask);
            if (mixed == 0) continue;
            const uint64_t rows = pack_rows(m00, m01, m10, m11);
            while (mixed != 0) {
                tris += tb.triangles_of_key[cell_key(rows, __builtin_ctz(mixed))];
                mixed &= mixed - 1;
            }
        }
    }
    bc.triangles = tris;
}

template <bool Interior, int Axis>
uint32_t emit_axis_vertices(const Context& cx, const BlockCells& bc, const float* pad, int i0, int j0, int k0,
                            uint16_t* local_id, uint32_t n) {
    const SampleGrid& g = *cx.grid;
    const float threshold = cx.threshold;
    constexpr int kStride[3] = {1, P, P * P};
    const int n_axis[3] = {g.nx, g.ny, g.nz};
    const int origin_axis[3] = {i0, j0, k0};
    // extract_surface's gradient_at: central differences, one-sided on the grid border.
    const auto gradient = [&](int p, int x, int y, int z) {
        if constexpr (Interior) {
            return Vec3((pad[p + 1] - pad[p - 1]) / 2.0f, (pad[p + P] - pad[p - P]) / 2.0f,
                        (pad[p + P * P] - pad[p - P * P]) / 2.0f);
        } else {
            const int local[3] = {x, y, z};
            float d[3];
            for (int a = 0; a < 3; ++a) {
                const int at = origin_axis[a] + local[a];
                const int lo = at > 0 ? 1 : 0;
                const int hi = at < n_axis[a] - 1 ? 1 : 0;
                d[a] = (pad[p + hi * kStride[a]] - pad[p - lo * kStride[a]]) / static_cast<float>(hi + lo);
            }
            return Vec3(d[0], d[1], d[2]);
        }
    };

    Vec3* positions = cx.out->positions.data() + bc.first_vertex;
    Vec3* normals = cx.out->normals.data() + bc.first_vertex;
    constexpr int s = kStride[Axis];
    for (int r = 0; r < B * B; ++r) {
        unsigned e = bc.edges[Axis][r];
        if (e == 0) continue;
        const int y = r % B, z = r / B;
        const int row = P * ((y + 1) + P * (z + 1)) + 1;
        while (e != 0) {
            const int x = __builtin_ctz(e);
            e &= e - 1;
            // extract_surface's add_vertex, with the same expressions.
            const int p0 = row + x, p1 = p0 + s;
            const float a = pad[p0];
            const float b = pad[p1];
            float t = (threshold - a) / (b - a);
            if (!(t >= 0.0f && t <= 1.0f)) t = 0.5f;  // NaN or infinite sample: the edge's midpoint

            Vec3 pos = g.origin + g.spacing * Vec3(float(i0 + x), float(j0 + y), float(k0 + z));
            pos[Axis] += t * g.spacing;

            const Vec3 g0 = gradient(p0, x, y, z);
            const Vec3 g1 = gradient(p1, x + (Axis == 0), y + (Axis == 1), z + (Axis == 2));
            Vec3 nrm = -((1.0f - t) * g0 + t * g1);
            const float len2 = glm::dot(nrm, nrm);
            if (len2 > 0.0f && std::isfinite(len2)) {
                nrm /= std::sqrt(len2);
            } else {
                // No usable gradient: point along the edge, from inside to outside.
                nrm = Vec3(0.0f);
                nrm[Axis] = is_inside(a, threshold) ? 1.0f : -1.0f;
            }
            positions[n] = pos;
            normals[n] = nrm;
            local_id[Axis * B * B * B + x + B * r] = static_cast<uint16_t>(n);
            ++n;
        }
    }
    return n;
}

/// The vertices of one block's crossed edges, written at first_vertex + rank (x edges,
/// then y, then z, each in bit order), and their block-local indices into local_id.
/// `pad` holds samples [-1, 9]^3 around the block. The arithmetic is extract_surface's
/// add_vertex and gradient_at, expression for expression; Interior: no sample used is on
/// the grid border, so every difference is central (the general path gives the same values).
template <bool Interior>
void emit_vertices(const Context& cx, const BlockCells& bc, const float* pad, int i0, int j0, int k0,
                   uint16_t* local_id) {
    uint32_t n = emit_axis_vertices<Interior, 0>(cx, bc, pad, i0, j0, k0, local_id, 0);
    n = emit_axis_vertices<Interior, 1>(cx, bc, pad, i0, j0, k0, local_id, n);
    emit_axis_vertices<Interior, 2>(cx, bc, pad, i0, j0, k0, local_id, n);
}

/// Pass 2 for one candidate: its vertices and triangles, at their final places.
void emit(const Context& cx, const BlockCells& bc) {
    const Tables& tb = tables();
    const SparseField& f = *cx.field;
    const SampleGrid& g = *cx.grid;
    int bi, bj, bk;
    cx.block_coords(bc.block, bi, bj, bk);
    const int i0 = bi * B, j0 = bj * B, k0 = bk * B;
    // Block-local index of each owned crossed edge's vertex, by axis and sample (x + 8 y +
    // 64 z); entries of edges that do not cross are never written nor read.
    uint16_t local_id[3 * B * B * B];

    if (bc.vertices > 0) {
        // Samples [-1, 9]^3 around the block from its 27 neighbourhood blocks (0 where
        // absent or beyond the grid; values beyond the grid are never read: the gradient
        // is one-sided there).
        const float* nb[3][3][3];  // [z][y][x], index 0 = the -1 neighbour
        for (int dz = 0; dz < 3; ++dz)
            for (int dy = 0; dy < 3; ++dy)
                for (int dx = 0; dx < 3; ++dx) nb[dz][dy][dx] = cx.block(bi + dx - 1, bj + dy - 1, bk + dz - 1);
        float pad[P * P * P];
        for (int z = -1; z <= B + 1; ++z) {
            const int zb = z < 0 ? 0 : z < B ? 1 : 2, rz = (z + B) % B;
            for (int y = -1; y <= B + 1; ++y) {
                const int yb = y < 0 ? 0 : y < B ? 1 : 2, ry = (y + B) % B;
                float* dst = pad + P * ((y + 1) + P * (z + 1));
                const int off = B * (ry + B * rz);
                const float* left = nb[zb][yb][0];
                const float* mid = nb[zb][yb][1];
                const float* right = nb[zb][yb][2];
                dst[0] = left ? left[off + B - 1] : 0.0f;
                if (mid) std::memcpy(dst + 1, mid + off, B * sizeof(float));
                else std::fill(dst + 1, dst + 1 + B, 0.0f);
                dst[B + 1] = right ? right[off] : 0.0f;
                dst[B + 2] = right ? right[off + 1] : 0.0f;
            }
        }
        const bool interior = i0 >= 1 && j0 >= 1 && k0 >= 1 && i0 + B <= g.nx - 2 && j0 + B <= g.ny - 2 &&
                              k0 + B <= g.nz - 2;
        if (interior) emit_vertices<true>(cx, bc, pad, i0, j0, k0, local_id);
        else emit_vertices<false>(cx, bc, pad, i0, j0, k0, local_id);
    }

    if (bc.triangles == 0) return;
    // Owners of the edges a cell can use: this block (0) and its +x (1), +y (2), +z (4)
    // neighbours and their sums (bit 0: x, bit 1: y, bit 2: z). Any block owning a crossed
    // edge is a candidate; a missing owner is only ever asked for rows without crossings.
    static const BlockCells kNone{};
    const BlockCells* owner[8];
    for (int o = 0; o < 8; ++o) {
        owner[o] = &kNone;
        const int ni = bi + (o & 1), nj = bj + ((o >> 1) & 1), nk = bk + ((o >> 2) & 1);
        if (ni >= f.blocks_x() || nj >= f.blocks_y() || nk >= f.blocks_z()) continue;
        const int32_t c = cx.candidate_of_block[f.block_index(ni, nj, nk)];
        if (c >= 0) owner[o] = cx.cells + c;
    }
    uint32_t* idx = cx.out->indices.data() + 3 * static_cast<size_t>(bc.first_triangle);
    const unsigned cell_mask = (1u << bc.ex) - 1u;
    for (int z = 0; z < bc.ez; ++z) {
        for (int y = 0; y < bc.ey; ++y) {
            const unsigned m00 = bc.inside[y + 9 * z], m10 = bc.inside[y + 1 + 9 * z];
            const unsigned m01 = bc.inside[y + 9 * (z + 1)], m11 = bc.inside[y + 1 + 9 * (z + 1)];
            unsigned mixed = mixed_cells(m00, m01, m10, m11, cell_mask);
            if (mixed == 0) continue;
            // Cells with all edges in this block (x, y, z < 7) read local_id. The others
            // (on the block's +x/+y/+z faces) use the 8 edge rows around this cell row
            // (see EdgeRef): the owner's crossed-edge bits and the vertex index of the
            // row's first edge (base8: the +x owner's, for x + dx == 8).
            const unsigned via_rows = (y + 1 < B && z + 1 < B) ? (1u << (B - 1)) : 0xffu;
            uint32_t base[8], base8[8];
            unsigned bits[8];
            bool rows_ready = false;
            const auto setup_rows = [&] {
                constexpr int kAxis[8] = {0, 0, 0, 0, 1, 1, 2, 2};
                constexpr int kDy[8] = {0, 1, 0, 1, 0, 0, 0, 1};
                constexpr int kDz[8] = {0, 0, 1, 1, 0, 1, 0, 0};
                for (int er = 0; er < 8; ++er) {
                    const int axis = kAxis[er];
                    const int ey = y + kDy[er], ez = z + kDz[er];
                    const int o = ((ey >> 3) << 1) | ((ez >> 3) << 2);
                    const int r = (ey & 7) + B * (ez & 7);
                    const BlockCells& ob = *owner[o];
                    bits[er] = ob.edges[axis][r];
                    base[er] = ob.first_vertex + ob.word_base[axis][r >> 3] + ob.prefix[axis][r];
                    const BlockCells& ox = *owner[o | 1];
                    base8[er] = ox.first_vertex + ox.word_base[axis][r >> 3] + ox.prefix[axis][r];
                }
                rows_ready = true;
            };
            const uint64_t rows = pack_rows(m00, m01, m10, m11);
            const int cell_row = B * (y + B * z);
            while (mixed != 0) {
                const int x = __builtin_ctz(mixed);
                mixed &= mixed - 1;
                const unsigned key = cell_key(rows, x);
                // Vertex index of each crossed cell edge, then the triangles.
                uint32_t id[12];
                unsigned crossed = tb.edges_of_key[key];
                if (((via_rows >> x) & 1u) == 0) {
                    const uint16_t* ids = local_id + cell_row + x;
                    while (crossed != 0) {
                        const int e = __builtin_ctz(crossed);
                        crossed &= crossed - 1;
                        id[e] = bc.first_vertex + ids[tb.local_offset[e]];
                    }
                } else {
                    if (!rows_ready) setup_rows();
                    while (crossed != 0) {
                        const int e = __builtin_ctz(crossed);
                        crossed &= crossed - 1;
                        const EdgeRef ref = tb.edge_ref[e];
                        const int ex = x + ref.dx;
                        id[e] = ex < B ? base[ref.row] + tb.below[bits[ref.row]][ex] : base8[ref.row];
                    }
                }
                const int8_t* tri = mc::kTriTable[tb.cube_of_key[key]].data();
                for (int k = tb.triangles_of_key[key]; k > 0; --k, tri += 3, idx += 3) {
                    idx[0] = id[tri[0]];
                    idx[1] = id[tri[1]];
                    idx[2] = id[tri[2]];
                }
            }
        }
    }
}

}  // namespace

void extract_surface_sparse(const SparseField& field, float threshold, SurfaceMesh& out, SurfaceWorkspace& ws) {
    auto t0 = std::chrono::steady_clock::now();
    if (!ws.impl) ws.impl = std::make_unique<SurfaceWorkspace::Impl>();
    SurfaceWorkspace::Impl& w = *ws.impl;
    ws.stats = SurfaceStats{};
    const SampleGrid& g = field.grid();
    const size_t nblocks = field.block_count();
    ws.stats.blocks = nblocks;
    if (g.nx < 2 || g.ny < 2 || g.nz < 2) {
        out.clear();
        return;
    }

    // Select: candidates in block order.
    const bool zero_inside = is_inside(0.0f, threshold);
    w.candidate_of_block.resize(nblocks);
    w.candidates.clear();
    const int bx = field.blocks_x(), by = field.blocks_y(), bz = field.blocks_z();
    for (int bk = 0; bk < bz; ++bk) {
        for (int bj = 0; bj < by; ++bj) {
            for (int bi = 0; bi < bx; ++bi) {
                const size_t blk = field.block_index(bi, bj, bk);
                bool any_in = false, any_out = false;
                for (int o = 0; o < 8; ++o) {
                    const int ni = bi + (o & 1), nj = bj + ((o >> 1) & 1), nk = bk + ((o >> 2) & 1);
                    if (ni >= bx || nj >= by || nk >= bz) continue;
                    const int32_t s = field.slot(ni, nj, nk);
                    if (s == SparseField::kNoBlock) {
                        (zero_inside ? any_in : any_out) = true;
                    } else {
                        any_in = any_in || is_inside(field.block_max(s), threshold);
                        any_out = any_out || !is_inside(field.block_min(s), threshold);
                    }
                }
                if (any_in && any_out) {
                    w.candidate_of_block[blk] = static_cast<int32_t>(w.candidates.size());
                    w.candidates.push_back(static_cast<uint32_t>(blk));
                } else {
                    w.candidate_of_block[blk] = -1;
                }
            }
        }
    }
    const size_t ncells = w.candidates.size();
    ws.stats.candidate_blocks = ncells;
    // Pass-1 records: grown, never shrunk, never cleared (classify writes every field).
    if (w.cells.size() < ncells) w.cells.resize(ncells);
    ws.stats.ms_select = ms_since(t0);

    Context cx{&field, &g, threshold, zero_inside ? 0x1ffu : 0u, w.candidate_of_block.data(), w.cells.data(), &out};

    // Pass 1.
    t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, ncells), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t c = r.begin(); c != r.end(); ++c) {
            w.cells[c].block = w.candidates[c];
            classify(cx, w.cells[c]);
        }
    });
    ws.stats.ms_classify = ms_since(t0);

    // Offsets.
    t0 = std::chrono::steady_clock::now();
    size_t vertices = 0, triangles = 0, active = 0;
    for (size_t c = 0; c < ncells; ++c) {
        BlockCells& bc = w.cells[c];
        bc.first_vertex = static_cast<uint32_t>(vertices);
        bc.first_triangle = static_cast<uint32_t>(triangles);
        vertices += bc.vertices;
        triangles += bc.triangles;
        active += (bc.vertices | bc.triangles) != 0;
    }
    out.positions.resize(vertices);
    out.normals.resize(vertices);
    out.indices.resize(3 * triangles);
    ws.stats.active_blocks = active;
    ws.stats.vertices = vertices;
    ws.stats.triangles = triangles;
    ws.stats.ms_offsets = ms_since(t0);

    // Pass 2.
    t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, ncells), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t c = r.begin(); c != r.end(); ++c) {
            const BlockCells& bc = w.cells[c];
            if ((bc.vertices | bc.triangles) != 0) emit(cx, bc);
        }
    });
    ws.stats.ms_emit = ms_since(t0);
}

}  // namespace mr
