// metariver surface, private: the blocks, tables and passes of extract_surface_sparse
// (marching_cubes_sparse.cpp has the algorithm's description and the driver; pass 1,
// classify, is in mc_sparse_classify.cpp, pass 2, emit, in marching_cubes_sparse.cpp).
#pragma once

#include <metariver/surface.h>

#include <array>
#include <cstdint>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mr::mcs {

constexpr int B = SparseField::kBlock;
constexpr int P = B + 3;  // padded block edge: samples -1 .. 9

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

/// The tables, built once (mc_sparse_classify.cpp).
const Tables& tables();

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

/// Cell row (y, z) of a classified block: its cells with corners on both sides (bit x)
/// and its four sample rows packed for cell_key.
struct CellRow {
    unsigned mixed;
    uint64_t rows;
};
inline CellRow cell_row(const BlockCells& bc, int y, int z, unsigned cell_mask) {
    const unsigned m00 = bc.inside[y + 9 * z], m10 = bc.inside[y + 1 + 9 * z];
    const unsigned m01 = bc.inside[y + 9 * (z + 1)], m11 = bc.inside[y + 1 + 9 * (z + 1)];
    return {mixed_cells(m00, m01, m10, m11, cell_mask), pack_rows(m00, m01, m10, m11)};
}


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

/// Pass 1 for one candidate: inside bits, crossed owned edges and their ranks, triangle count.
void classify(const Context& cx, BlockCells& bc);
/// Pass 2 for one candidate: its vertices and triangles, at their final places.
void emit(const Context& cx, const BlockCells& bc);

}  // namespace mr::mcs
