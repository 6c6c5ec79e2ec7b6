// The paper's metaball field (section 2.1, eq. 2): a grid over the balls' bounding box
// grown by an offset, `resolution` cells per metre; each sample is the sum over every
// active ball of the falloff (1/r^2 in the paper's text, radius/r in its code) divided
// by (active balls + 1). Every ball touches every sample: O(balls x samples), the
// paper's second bottleneck, kept as the reference for the compact-kernel fields.
#include <metariver/field.h>

#include <algorithm>
#include <cmath>

namespace mr {

std::string_view to_string(FieldKernel k) {
    switch (k) {
        case FieldKernel::InverseSquare: return "inverse_square";
        case FieldKernel::RadiusOverR: return "radius_over_r";
        case FieldKernel::Poly6: return "poly6";
        case FieldKernel::W1: return "w1";
    }
    return "?";
}

std::string_view to_string(FieldBounds b) {
    switch (b) {
        case FieldBounds::Particles: return "particles";
        case FieldBounds::Terrain: return "terrain";
    }
    return "?";
}

namespace {
/// Smallest r^2 (m^2) used, so a sample exactly on a ball centre stays finite.
constexpr float kMinR2 = 1e-6f;

template <class Falloff>
void accumulate(std::span<const Vec3> balls, ScalarGrid& g, float scale, Falloff falloff) {
    for (int k = 0; k < g.nz; ++k) {
        for (int j = 0; j < g.ny; ++j) {
            float* row = g.values.data() + g.index(0, j, k);
            const float y = g.origin.y + g.spacing * static_cast<float>(j);
            const float z = g.origin.z + g.spacing * static_cast<float>(k);
            for (int i = 0; i < g.nx; ++i) {
                const float x = g.origin.x + g.spacing * static_cast<float>(i);
                float sum = 0.0f;
                for (const Vec3& b : balls) {
                    const float dx = x - b.x, dy = y - b.y, dz = z - b.z;
                    sum += falloff(std::max(dx * dx + dy * dy + dz * dz, kMinR2));
                }
                row[i] = sum * scale;
            }
        }
    }
}
}  // namespace

bool compute_field_paper(std::span<const Vec3> balls, const FieldDef& def, ScalarGrid& out) {
    if (balls.empty()) {
        out.reset(0, 0, 0, Vec3(0.0f), 1.0f / def.resolution);
        return true;
    }
    Aabb box;
    for (const Vec3& b : balls) box.grow(b);
    box.min -= Vec3(def.bounds_offset);
    box.max += Vec3(def.bounds_offset);
    const float h = 1.0f / def.resolution;
    const Vec3 ext = box.extent();
    const auto samples = [&](float e) { return static_cast<long long>(std::ceil(e * def.resolution)) + 1; };
    const long long nx = samples(ext.x), ny = samples(ext.y), nz = samples(ext.z);
    if (static_cast<double>(nx) * ny * nz > static_cast<double>(kMaxFieldSamples)) {
        out.reset(0, 0, 0, box.min, h);
        return false;
    }
    out.reset(int(nx), int(ny), int(nz), box.min, h);
    const float scale = 1.0f / static_cast<float>(balls.size() + 1);
    if (def.kernel == FieldKernel::InverseSquare) {
        accumulate(balls, out, scale, [](float r2) { return 1.0f / r2; });
    } else if (def.kernel == FieldKernel::Poly6) {
        // Dense twin of the sparse path (tests): a sum, not a mean, compact support.
        const float inv_r2 = 1.0f / (def.radius * def.radius);
        accumulate(balls, out, 1.0f, [inv_r2](float r2) {
            const float q = 1.0f - r2 * inv_r2;
            return q > 0.0f ? q * q * q : 0.0f;
        });
    } else if (def.kernel == FieldKernel::RadiusOverR) {
        const float radius = def.radius;
        accumulate(balls, out, scale, [radius](float r2) { return radius / std::sqrt(r2); });
    } else {  // W1: its strength and subtract are a KernelDef's (the sparse field)
        out.reset(0, 0, 0, box.min, h);
        return false;
    }
    return true;
}

}  // namespace mr
