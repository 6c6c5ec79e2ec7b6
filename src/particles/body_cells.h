// The bodies' broad phase for the water (pbf_bodies.cpp): their bounding spheres binned in
// a grid over x and z, so a particle tests only the bodies listed in its cell instead of
// every body's sphere. A cell lists its bodies in index order: a particle meets them in the
// order a loop over all bodies would, and the results do not change.
#pragma once

#include <metariver/core.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

namespace mr {

class BodyCells {
public:
    /// Bins the spheres (centre, radius^2); a non-finite one is left out of every cell.
    void build(const std::vector<glm::vec4>& spheres) {
        // Each sphere's square over x and z, widened past the rounding of the sphere test.
        std::vector<glm::vec4> box;  // x from, x to, z from, z to
        float cell = 0.0f, lx = 0.0f, hx = 0.0f, lz = 0.0f, hz = 0.0f;
        for (const glm::vec4& s : spheres) {
            const float r = std::sqrt(s.w) * 1.001f + 1e-4f;
            const glm::vec4 b(s.x - r, s.x + r, s.z - r, s.z + r);
            if (!std::isfinite(b.x + b.y + b.z + b.w)) {
                box.push_back(glm::vec4(NAN));
                continue;
            }
            lx = cell > 0.0f ? std::min(lx, b.x) : b.x, hx = cell > 0.0f ? std::max(hx, b.y) : b.y;
            lz = cell > 0.0f ? std::min(lz, b.z) : b.z, hz = cell > 0.0f ? std::max(hz, b.w) : b.w;
            cell = std::max(cell, 2.0f * r);
            box.push_back(b);
        }
        nx_ = nz_ = 0;
        first_.assign(1, 0);
        ids_.clear();
        if (!(cell > 0.0f)) return;
        // Cells about a sphere's width; wider where the bodies are far apart (at most
        // kMaxSide a side, about kMaxCells in all); one cell for all where the span overflows.
        const float w = hx - lx, h = hz - lz;
        x0_ = lx, z0_ = lz;
        if (std::isfinite(w) && std::isfinite(h)) {
            cell = std::max({cell, w / float(kMaxSide), h / float(kMaxSide)});
            const float cells = (w / cell) * (h / cell);
            if (cells > float(kMaxCells)) cell *= std::sqrt(cells / float(kMaxCells));
            inv_cell_ = 1.0f / cell;
            nx_ = std::clamp(int(w * inv_cell_) + 1, 1, kMaxSide + 1);
            nz_ = std::clamp(int(h * inv_cell_) + 1, 1, kMaxSide + 1);
        } else {  // every finite x in cell 0
            x0_ = z0_ = inv_cell_ = 0.0f, nx_ = nz_ = 1;
        }
        const auto index = [&](float c, float o, int n) { return std::clamp(int((c - o) * inv_cell_), 0, n - 1); };
        first_.assign(size_t(nx_) * size_t(nz_) + 1, 0);
        for (int pass = 0; pass < 2; ++pass) {  // count, then fill (bodies in index order)
            if (pass) {
                for (size_t c = 1; c < first_.size(); ++c) first_[c] += first_[c - 1];
                ids_.resize(first_.back());
            }
            for (size_t b = 0; b < box.size(); ++b) {
                if (!std::isfinite(box[b].x)) continue;
                for (int k = index(box[b].z, z0_, nz_); k <= index(box[b].w, z0_, nz_); ++k)
                    for (int i = index(box[b].x, x0_, nx_); i <= index(box[b].y, x0_, nx_); ++i) {
                        const size_t c = size_t(k) * size_t(nx_) + size_t(i);
                        if (pass) {
                            ids_[first_[c]++] = uint32_t(b);
                        } else {
                            ++first_[c + 1];
                        }
                    }
            }
        }
        for (size_t c = first_.size() - 1; c > 0; --c) first_[c] = first_[c - 1];  // back to the ranges' starts
        first_[0] = 0;
    }

    /// f(b) for each body b listed in the cell of x, in index order, until f returns true.
    template <class F>
    void visit(const Vec3& x, F&& f) const {
        const float u = (x.x - x0_) * inv_cell_, v = (x.z - z0_) * inv_cell_;
        if (!(u >= 0.0f && u < float(nx_) && v >= 0.0f && v < float(nz_))) return;  // NaN: outside
        const size_t c = size_t(v) * size_t(nx_) + size_t(u);
        for (uint32_t k = first_[c]; k < first_[c + 1]; ++k)
            if (f(size_t(ids_[k]))) return;
    }

private:
    float x0_ = 0.0f, z0_ = 0.0f, inv_cell_ = 0.0f;
    int nx_ = 0, nz_ = 0;
    static constexpr int kMaxCells = 1 << 12, kMaxSide = 1 << 10;
    std::vector<uint32_t> first_{0}, ids_;  ///< per cell its bodies' range in ids_ (CSR)
};

}  // namespace mr
