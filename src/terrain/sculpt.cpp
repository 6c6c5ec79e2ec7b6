// Sculpting (issue 14): brush strokes on a built terrain's heights, and undo.
#include <metariver/terrain.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr {

Result<TerrainEdit> Terrain::sculpt(const Brush& b) {
    if (!std::isfinite(b.x) || !std::isfinite(b.z)) return Error{"brush: centre: must be finite"};
    if (!std::isfinite(b.radius) || !(b.radius > 0.0f))
        return Error{fmt::format("brush: radius: must be finite and > 0 metres (got {})", b.radius)};
    const bool metres = b.mode == BrushMode::Raise || b.mode == BrushMode::Lower;
    if (!std::isfinite(b.strength) || b.strength < 0.0f || (!metres && b.strength > 1.0f))
        return Error{fmt::format("brush: strength: must be {} (got {})", metres ? ">= 0 metres" : "in [0, 1]", b.strength)};
    if (b.mode == BrushMode::Flatten && !std::isfinite(b.target)) return Error{"brush: target: must be finite"};
    const float s = area_scale_;
    const float x0 = vertices_.front().x, z0 = vertices_.front().z;
    TerrainEdit e;
    e.j0 = std::max(0, int(std::ceil((b.x - b.radius - x0) / s)));
    e.j1 = std::min(columns_ - 1, int(std::floor((b.x + b.radius - x0) / s)));
    e.i0 = std::max(0, int(std::ceil((b.z - b.radius - z0) / s)));
    e.i1 = std::min(rows_ - 1, int(std::floor((b.z + b.radius - z0) / s)));
    if (e.empty()) return e;
    const int w = e.j1 - e.j0 + 1;
    e.before.reserve(size_t(w) * size_t(e.i1 - e.i0 + 1));
    for (int i = e.i0; i <= e.i1; ++i)
        for (int j = e.j0; j <= e.j1; ++j) e.before.push_back(sample(i, j));
    const auto before = [&](int i, int j) {  // the heights before this stroke (smoothing reads them)
        if (i >= e.i0 && i <= e.i1 && j >= e.j0 && j <= e.j1) return e.before[size_t(i - e.i0) * w + (j - e.j0)];
        return sample(i, j);
    };
    for (int i = e.i0; i <= e.i1; ++i)
        for (int j = e.j0; j <= e.j1; ++j) {
            Vec3& v = vertices_[size_t(i) * columns_ + j];
            const float d2 = ((v.x - b.x) * (v.x - b.x) + (v.z - b.z) * (v.z - b.z)) / (b.radius * b.radius);
            if (d2 >= 1.0f) continue;
            const float weight = (1.0f - d2) * (1.0f - d2);
            const float h = before(i, j);
            switch (b.mode) {
                case BrushMode::Raise: v.y = h + b.strength * weight; break;
                case BrushMode::Lower: v.y = h - b.strength * weight; break;
                case BrushMode::Flatten: v.y = h + b.strength * weight * (b.target - h); break;
                case BrushMode::Smooth: {
                    double sum = 0.0;
                    int n = 0;
                    for (int a = std::max(0, i - 1); a <= std::min(rows_ - 1, i + 1); ++a)
                        for (int c = std::max(0, j - 1); c <= std::min(columns_ - 1, j + 1); ++c, ++n) sum += before(a, c);
                    v.y = h + b.strength * weight * (float(sum / n) - h);
                    break;
                }
            }
        }
    recompute_bounds();
    return e;
}

void Terrain::restore(const TerrainEdit& e) {
    if (e.empty() || e.i0 < 0 || e.j0 < 0 || e.i1 >= rows_ || e.j1 >= columns_) return;  // not this terrain's
    const int w = e.j1 - e.j0 + 1;
    if (e.before.size() != size_t(w) * size_t(e.i1 - e.i0 + 1)) return;
    for (int i = e.i0; i <= e.i1; ++i)
        for (int j = e.j0; j <= e.j1; ++j)
            vertices_[size_t(i) * columns_ + j].y = e.before[size_t(i - e.i0) * w + (j - e.j0)];
    recompute_bounds();
}

}  // namespace mr
