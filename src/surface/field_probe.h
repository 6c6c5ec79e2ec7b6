// metariver surface: trilinear reads of a SparseField at arbitrary points (the smoothing's
// feature weights, src/surface/smoothing.cpp).
#pragma once

#include <metariver/sparse_field.h>

#include <algorithm>
#include <cstdint>

namespace mr {

/// Reads a SparseField at arbitrary points (trilinear; 0 outside the grid and where no
/// block is stored). Everything it needs is copied out of the field once, so the loop
/// that stores weights does not re-read the field's members after every store.
class FieldProbe {
public:
    explicit FieldProbe(const SparseField& f)
        : f_(f), origin_(f.grid().origin), inv_(1.0f / f.grid().spacing), hi_(float(f.grid().nx - 1), float(f.grid().ny - 1), float(f.grid().nz - 1)),
          nx2_(f.grid().nx - 2), ny2_(f.grid().ny - 2), nz2_(f.grid().nz - 2), bx_(f.blocks_x()), by_(f.blocks_y()),
          dir_(f.directory().data()) {}

    /// The value at p, or `floor` when the blocks holding its 8 samples all stay at or
    /// below `floor` (their block max): the caller only needs to know that much, and the
    /// blocks' maxima are small and cached where the samples may not be.
    float at(const Vec3& p, float floor) const {
        constexpr unsigned B = SparseField::kBlock;
        static_assert(B == 8, "the shifts and masks below assume 8^3 blocks");
        const Vec3 q = (p - origin_) * inv_;
        if (!(q.x >= 0.0f && q.y >= 0.0f && q.z >= 0.0f && q.x <= hi_.x && q.y <= hi_.y && q.z <= hi_.z)) return 0.0f;
        const int i = std::min(static_cast<int>(q.x), nx2_);
        const int j = std::min(static_cast<int>(q.y), ny2_);
        const int k = std::min(static_cast<int>(q.z), nz2_);
        const float tx = q.x - float(i), ty = q.y - float(j), tz = q.z - float(k);
        const unsigned ui = unsigned(i), uj = unsigned(j), uk = unsigned(k);
        float c[8];
        if ((ui & 7u) != 7u && (uj & 7u) != 7u && (uk & 7u) != 7u) {  // all 8 samples in one block
            const int32_t s = dir_[size_t(ui >> 3) + size_t(bx_) * (size_t(uj >> 3) + size_t(by_) * size_t(uk >> 3))];
            if (s == SparseField::kNoBlock || f_.block_max(s) <= floor) return floor;
            const float* v = f_.block_values(s) + (ui & 7u) + B * ((uj & 7u) + B * (uk & 7u));
            c[0] = v[0], c[1] = v[1], c[2] = v[B], c[3] = v[B + 1];
            c[4] = v[B * B], c[5] = v[B * B + 1], c[6] = v[B * B + B], c[7] = v[B * B + B + 1];
        } else {
            int32_t slot[8];
            bool above = false;
            for (unsigned n = 0; n < 8; ++n) {
                const unsigned x = ui + (n & 1u), y = uj + ((n >> 1) & 1u), z = uk + (n >> 2);
                slot[n] = dir_[size_t(x >> 3) + size_t(bx_) * (size_t(y >> 3) + size_t(by_) * size_t(z >> 3))];
                above |= slot[n] != SparseField::kNoBlock && f_.block_max(slot[n]) > floor;
            }
            if (!above) return floor;
            for (unsigned n = 0; n < 8; ++n) {
                const unsigned x = ui + (n & 1u), y = uj + ((n >> 1) & 1u), z = uk + (n >> 2);
                c[n] = slot[n] == SparseField::kNoBlock ? 0.0f
                                                         : f_.block_values(slot[n])[(x & 7u) + B * ((y & 7u) + B * (z & 7u))];
            }
        }
        const auto lerp = [](float a, float b, float t) { return a + t * (b - a); };
        const float y0 = lerp(lerp(c[0], c[1], tx), lerp(c[2], c[3], tx), ty);
        const float y1 = lerp(lerp(c[4], c[5], tx), lerp(c[6], c[7], tx), ty);
        return lerp(y0, y1, tz);
    }

private:
    const SparseField& f_;
    Vec3 origin_;
    float inv_;
    Vec3 hi_;
    int nx2_, ny2_, nz2_, bx_, by_;
    const int32_t* dir_;
};

}  // namespace mr
