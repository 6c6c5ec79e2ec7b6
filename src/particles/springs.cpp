// The paper's spring forces (section 2.3.1, eq. 3) as its code computes them:
// for each pair of active particles, v = p_i - p_j; when |v| - r < max_distance,
// a = 0.5 * k * (r * v/|v| - v) pushes i towards rest length r and j by the opposite
// amount, so every pair conserves momentum. The all-pairs loop is O(N^2) on purpose:
// it is the reference the neighbour-grid path is checked against.
#include <metariver/particles.h>

namespace mr {

void add_spring_forces_pairs(Particles& p, const SpringDef& def) {
    if (def.stiffness == 0.0f) return;
    const size_t n = p.size();
    const float half_k = 0.5f * def.stiffness;
    const float r = def.min_distance;
    for (size_t i = 0; i < n; ++i) {
        if (!p.active[i]) continue;
        const Vec3 pi = p.position[i];
        Vec3 acc_i(0.0f);
        for (size_t j = i + 1; j < n; ++j) {
            if (!p.active[j]) continue;
            const Vec3 v = pi - p.position[j];
            const float len = glm::length(v);
            if (len <= 0.0f || len - r >= def.max_distance) continue;
            const Vec3 a = half_k * (r * (v / len) - v);
            acc_i += a;
            p.force[j] -= a;
        }
        p.force[i] += acc_i;
    }
}

}  // namespace mr
