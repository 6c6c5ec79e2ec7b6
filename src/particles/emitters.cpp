// Emitters and sinks (see emitters.h): the names of their kinds and keys, and the
// outflow meter.
#include <metariver/emitters.h>

#include <cmath>
#include <string>

namespace mr {

std::string_view to_string(SourceShape s) {
    switch (s) {
        case SourceShape::Box: return "box";
        case SourceShape::Disc: return "disc";
        case SourceShape::Point: return "point";
    }
    return "?";
}

std::string_view to_string(SinkKind s) {
    switch (s) {
        case SinkKind::None: return "none";
        case SinkKind::Box: return "box";
        case SinkKind::Edges: return "edges";
    }
    return "?";
}

std::string source_key(size_t k, SourceField f) {
    const char* main[] = {"particles.spawn_center", "particles.spawn_half_extent", "particles.flow_rate"};
    const char* entry[] = {"center", "half_extent", "flow_rate"};
    if (k == 0) return main[int(f)];
    return "particles.source[" + std::to_string(k) + "]." + entry[int(f)];
}

Vec3 source_half_size(SourceShape shape, const Vec3& h) {
    switch (shape) {
        case SourceShape::Box: return h;
        case SourceShape::Disc: return Vec3(h.x, h.y, h.x);
        case SourceShape::Point: return Vec3(0.0f);
    }
    return h;
}

void FlowMeter::record(double time_s, uint64_t sunk_total) {
    if (first_outflow_s_ < 0.0 && sunk_total > 0) first_outflow_s_ = time_s;
    const double r[2] = {time_s, double(sunk_total)};
    records_.push(r);
}

FlowMeter::Summary FlowMeter::summary() const {
    Summary s;
    s.first_outflow_s = first_outflow_s_;
    const size_t size = records_.size();
    if (size < 8) return s;
    const size_t last = size - 1, k0 = size / 2;
    auto rate = [&](size_t a, size_t b) {
        const double ta = records_[a][0], tb = records_[b][0];
        return tb > ta ? (records_[b][1] - records_[a][1]) / (tb - ta) : 0.0;
    };
    s.rate = rate(k0, last);
    bool steady = s.rate > 0.0;
    for (int q = 0; q < 4; ++q) {
        const size_t a = k0 + (last - k0) * size_t(q) / 4, b = k0 + (last - k0) * size_t(q + 1) / 4;
        s.windows[q] = rate(a, b);
        steady = steady && std::abs(s.windows[q] - s.rate) <= 0.25 * s.rate;
    }
    s.steady = steady;
    return s;
}

}  // namespace mr
