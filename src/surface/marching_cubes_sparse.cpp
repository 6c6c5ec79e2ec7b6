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

#include "mc_sparse_blocks.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstring>

namespace mr {

using namespace mcs;

namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

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

}  // namespace

void mcs::emit(const Context& cx, const BlockCells& bc) {
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
            auto [mixed, rows] = cell_row(bc, y, z, cell_mask);
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
            const int row_base = B * (y + B * z);
            while (mixed != 0) {
                const int x = __builtin_ctz(mixed);
                mixed &= mixed - 1;
                const unsigned key = cell_key(rows, x);
                // Vertex index of each crossed cell edge, then the triangles.
                uint32_t id[12];
                unsigned crossed = tb.edges_of_key[key];
                if (((via_rows >> x) & 1u) == 0) {
                    const uint16_t* ids = local_id + row_base + x;
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
