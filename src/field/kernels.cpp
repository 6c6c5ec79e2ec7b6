// metariver field: compact-support kernels and the W1 peer workload.
//
// W1: three.js MarchingCubes' addBall falloff, strength / (r^2 + 1e-6) - subtract where
// positive, as defined for the peers in ../shared/peers/README.md. Poly6: Wyvill's
// (1 - r^2/R^2)^3 (Wyvill, McPheeters, Wyvill 1986; "poly6" in Mueller, Charypar, Gross
// 2003), smooth and cheap (no square root), for the simulation's surface.
#include <metariver/sparse_field.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace mr {

KernelDef w1_kernel(float strength, float subtract) {
    KernelDef k;
    k.type = FieldKernel::W1;
    k.strength = strength;
    k.subtract = subtract;
    k.radius = std::sqrt(strength / subtract);
    return k;
}

KernelDef poly6_kernel(float radius, float amplitude) {
    KernelDef k;
    k.type = FieldKernel::Poly6;
    k.radius = radius;
    k.amplitude = amplitude;
    return k;
}

float kernel_value(const KernelDef& k, float r2) {
    if (!(r2 < k.radius * k.radius)) return 0.0f;
    if (k.type == FieldKernel::W1) {
        return std::max(0.0f, k.strength / (r2 + 1e-6f) - k.subtract);
    }
    const float q = 1.0f - r2 * (1.0f / (k.radius * k.radius));
    return k.amplitude * (q * q * q);
}

Status validate(const KernelDef& k) {
    if (k.type != FieldKernel::Poly6 && k.type != FieldKernel::W1)
        return Error{"kernel type must be a compact kernel (poly6 or w1), got " + std::string(to_string(k.type))};
    if (!std::isfinite(k.radius) || !(k.radius > 0.0f)) {
        return Error{"kernel radius must be finite and > 0 metres, got " + std::to_string(k.radius)};
    }
    if (k.type == FieldKernel::W1) {
        if (!std::isfinite(k.strength) || !(k.strength > 0.0f) || !std::isfinite(k.subtract) || !(k.subtract > 0.0f)) {
            return Error{"w1 kernel needs finite strength > 0 and subtract > 0"};
        }
    } else if (!std::isfinite(k.amplitude)) {
        return Error{"poly6 kernel amplitude must be finite"};
    }
    return Ok{};
}

std::vector<Vec3> w1_balls(int n, uint32_t seed) {
    Lcg rng(seed);
    std::vector<Vec3> balls(static_cast<size_t>(std::max(n, 0)));
    for (Vec3& b : balls) {
        const double x = 0.1 + 0.8 * rng.next();
        const double y = 0.1 + 0.8 * rng.next();
        const double z = 0.1 + 0.8 * rng.next();
        b = Vec3(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
    }
    return balls;
}

KernelDef w1_kernel_for(int n, float rcoef, float iso, float sub) {
    const double r = static_cast<double>(rcoef) * std::pow(static_cast<double>(std::max(n, 1)), -1.0 / 3.0);
    return w1_kernel(static_cast<float>((static_cast<double>(iso) + sub) * r * r), sub);
}

SampleGrid w1_grid(int res) {
    SampleGrid g;
    g.origin = Vec3(0.0f);
    g.spacing = res > 1 ? 1.0f / static_cast<float>(res - 1) : 1.0f;
    g.nx = g.ny = g.nz = std::max(res, 0);
    return g;
}

}  // namespace mr
