// metariver surface: pass 1 of extract_surface_sparse (see marching_cubes_sparse.cpp):
// per candidate block, the inside bits, the crossed owned edges with their ranks and the
// triangles of owned cells; and the tables both passes read.
#include "mc_sparse_blocks.h"

#include <algorithm>

namespace mr::mcs {

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
            auto [mixed, rows] = cell_row(bc, y, z, cell_mask);
            while (mixed != 0) {
                tris += tb.triangles_of_key[cell_key(rows, __builtin_ctz(mixed))];
                mixed &= mixed - 1;
            }
        }
    }
    bc.triangles = tris;
}

}  // namespace mr::mcs
