// Plausibility measures of a particle state that need the terrain: spray (particles
// thrown out of the water), water over the main channel (ChannelCoverage) and the
// outflow per outlet (OutletMeter).
#include <metariver/neighbor_grid.h>
#include <metariver/scene.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr {

float spray_fraction(const Terrain& terrain, std::span<const Vec3> positions, std::span<const uint8_t> active,
                     float kernel_radius, float spacing) {
    const size_t n = std::min(positions.size(), active.size());
    size_t count = 0;
    for (size_t i = 0; i < n; ++i) count += active[i] != 0;
    if (count == 0 || !(kernel_radius > 0.0f)) return 0.0f;

    NeighborGrid grid;
    grid.build(positions.first(n), active.first(n), kernel_radius);
    const float r2 = kernel_radius * kernel_radius;
    const float clearance = 2.0f * spacing;
    size_t spray = 0;
    for (size_t i = 0; i < n; ++i) {
        if (!active[i]) continue;
        const Vec3 p = positions[i];
        // Near the ground (or on it) a particle is water however alone it is.
        if (terrain.contains_xz(p.x, p.z) && !(p.y - terrain.height_mesh(p.x, p.z) > clearance)) continue;
        int neighbours = 0;
        grid.for_each_candidate(p, [&](uint32_t j) {
            const Vec3 d = positions[j] - p;
            neighbours += j != i && d.x * d.x + d.y * d.y + d.z * d.z < r2;
        });
        spray += neighbours < kSprayNeighbours;
    }
    return static_cast<float>(double(spray) / double(count));
}

ChannelCoverage::ChannelCoverage(const Terrain& t, std::span<const std::pair<int, int>> cells, float radius_samples,
                                 float depth)
    : rows_(t.rows()),
      columns_(t.columns()),
      scale_(t.area_scale()),
      radius_(radius_samples * t.area_scale()),
      depth_(depth),
      origin_(t.bounds().min.x, 0.0f, t.bounds().min.z),
      index_(size_t(t.rows()) * size_t(t.columns()), -1) {
    for (const auto& [i, j] : cells) {
        int32_t& k = index_[size_t(i) * size_t(columns_) + size_t(j)];
        if (k >= 0) continue;  // a cell counts once
        k = int32_t(cells_.size());
        cells_.emplace_back(i, j);
        ground_.push_back(t.sample(i, j));
    }
}

float ChannelCoverage::measure(std::span<const Vec3> positions, std::span<const uint8_t> active) const {
    if (cells_.empty()) return 0.0f;
    std::vector<uint8_t> covered(cells_.size(), 0);
    size_t count = 0;
    const size_t n = std::min(positions.size(), active.size());
    const float r2 = radius_ * radius_;
    // Cells within radius_ of a particle lie within `reach` cells of its nearest cell
    // (2 for 1.5 samples).
    const int reach = int(std::ceil(radius_ / scale_ + 0.5f));
    for (size_t k = 0; k < n; ++k) {
        if (!active[k]) continue;
        const Vec3 p = positions[k] - origin_;
        const float fi = p.z / scale_, fj = p.x / scale_;
        if (!(fi > -float(reach) - 1.0f && fi < float(rows_ + reach) && fj > -float(reach) - 1.0f &&
              fj < float(columns_ + reach)))
            continue;  // far outside the grid (or not finite)
        const int ci = int(std::lround(fi)), cj = int(std::lround(fj));
        for (int a = std::max(ci - reach, 0); a <= std::min(ci + reach, rows_ - 1); ++a)
            for (int b = std::max(cj - reach, 0); b <= std::min(cj + reach, columns_ - 1); ++b) {
                const int32_t c = index_[size_t(a) * size_t(columns_) + size_t(b)];
                if (c < 0 || covered[size_t(c)]) continue;
                const float dx = p.x - float(b) * scale_, dz = p.z - float(a) * scale_;
                if (dx * dx + dz * dz <= r2 && p.y - ground_[size_t(c)] <= depth_) {
                    covered[size_t(c)] = 1;
                    ++count;
                }
            }
    }
    return float(double(count) / double(cells_.size()));
}

float ChannelCoverage::measure(const HeightfieldWater& water, float wet_depth) const {
    if (cells_.empty() || water.rows != rows_ || water.columns != columns_) return 0.0f;
    const int reach = int(std::floor(radius_ / scale_));
    size_t count = 0;
    for (const auto& [i, j] : cells_) {
        bool wet = false;
        for (int a = std::max(i - reach, 0); a <= std::min(i + reach, rows_ - 1) && !wet; ++a)
            for (int b = std::max(j - reach, 0); b <= std::min(j + reach, columns_ - 1) && !wet; ++b) {
                const float da = float(a - i) * scale_, db = float(b - j) * scale_;
                wet = da * da + db * db <= radius_ * radius_ && water.depth[size_t(a) * size_t(columns_) + size_t(b)] > wet_depth;
            }
        count += wet;
    }
    return float(double(count) / double(cells_.size()));
}

OutletMeter::OutletMeter(const Terrain& t, const ChannelMap& m, std::pair<int, int> main_outlet) {
    const float s = t.area_scale();
    auto add = [&](int i, int j, uint32_t acc) {
        outlets_.push_back(Outlet{.row = i, .column = j, .x = t.bounds().min.x + float(j) * s,
                                  .z = t.bounds().min.z + float(i) * s, .accumulation = acc,
                                  .main = std::pair(i, j) == main_outlet});
    };
    for (const ChannelMap::Outlet& o : m.outlets()) add(o.row, o.column, o.accumulation);
    if (std::none_of(outlets_.begin(), outlets_.end(), [](const Outlet& o) { return o.main; }))
        add(main_outlet.first, main_outlet.second, m.accumulation(main_outlet.first, main_outlet.second));
    x0_ = t.bounds().min.x;
    x1_ = t.bounds().max.x;
    z0_ = t.bounds().min.z;
    z1_ = t.bounds().max.z;
    radius_ = std::max(3.0f * s, 3.0f);
    records_ = Checkpoints(kOutletRecords, outlets_.size() + 2);
    total_.assign(outlets_.size() + 1, 0.0);
    first_s_.assign(outlets_.size() + 1, -1.0);
    row_.assign(outlets_.size() + 2, 0.0);
}

int OutletMeter::assign(const Vec3& exit) const {
    if (!std::isfinite(exit.x) || !std::isfinite(exit.z)) return -1;
    // The exit projected onto the rectangle: on its border for a particle over an edge.
    const float x = std::clamp(exit.x, x0_, x1_), z = std::clamp(exit.z, z0_, z1_);
    int best = -1;
    float best_d2 = radius_ * radius_;
    // The river's mouth first: an exit within the radius of the main outlet is the
    // river's even where a smaller outlet cell lies nearer (a wide mouth spans several).
    for (size_t k = 0; k < outlets_.size(); ++k)
        if (outlets_[k].main) {
            const float dx = x - outlets_[k].x, dz = z - outlets_[k].z;
            if (dx * dx + dz * dz <= best_d2) return int(k);
        }
    for (size_t k = 0; k < outlets_.size(); ++k) {
        const float dx = x - outlets_[k].x, dz = z - outlets_[k].z;
        const float d2 = dx * dx + dz * dz;
        if (d2 < best_d2 || (best < 0 && d2 == best_d2)) {
            best_d2 = d2;
            best = int(k);
        }
    }
    return best;
}

void OutletMeter::record(double time_s, std::span<const Vec3> exits) {
    for (const Vec3& e : exits) {
        const int o = assign(e);
        const size_t k = o < 0 ? outlets_.size() : size_t(o);
        total_[k] += 1.0;
        if (first_s_[k] < 0.0) first_s_[k] = time_s;
    }
    row_[0] = time_s;
    std::copy(total_.begin(), total_.end(), row_.begin() + 1);
    records_.push(row_);
}

OutletMeter::Summary OutletMeter::summary() const {
    Summary s;
    s.outlets.resize(outlets_.size());
    // The second half as FlowMeter measures it: the exits of frame records (k0, last].
    const size_t n = records_.size();
    const size_t last = n ? n - 1 : 0, k0 = n / 2;
    const double span = n >= 8 && records_[last][0] > records_[k0][0] ? records_[last][0] - records_[k0][0] : 0.0;
    for (size_t k = 0; k <= outlets_.size(); ++k) {
        Count& c = k < outlets_.size() ? s.outlets[k] : s.other;
        c.particles = uint64_t(total_[k]);
        c.first_s = first_s_[k];
        if (span > 0.0) c.rate = (records_[last][1 + k] - records_[k0][1 + k]) / span;
    }
    for (size_t k = 0; k < outlets_.size(); ++k)
        if (outlets_[k].main) s.main = s.outlets[k];
    return s;
}

}  // namespace mr
