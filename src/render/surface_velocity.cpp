// The fluid's velocity at the water surface's vertices, for the flow detail of the
// water shader (docs/rendering.md, "Flow detail").
//
// Per vertex x: the Shepard-normalised SPH average of the velocities of the active
// particles within R,  v(x) = sum_j W(|x - x_j|) v_j / sum_j W(|x - x_j|),  with the
// poly6 weight W(r) = (1 - r^2/R^2)^3 (Mueller et al. 2003), and v(x) = 0 where no
// particle lies within R. The fast path bins the particles in a NeighborGrid of cell R
// and gathers per vertex in parallel (each vertex writes its own slot, candidates in
// the grid's fixed order: the same result for any thread count); the twin visits every
// particle for every vertex.
#include <metariver/render.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace mr::render {

namespace {

/// The poly6 weight of a squared distance d2 for 1/R^2 = inv_r2; 0 at and beyond R.
inline float poly6(float d2, float inv_r2) {
    const float q = 1.0f - d2 * inv_r2;
    return q > 0.0f ? q * q * q : 0.0f;
}

inline Vec3 normalised(const Vec3& sum, float weight) { return weight > 0.0f ? sum / weight : Vec3(0.0f); }

}  // namespace

void surface_velocities(std::span<const Vec3> vertices, const Particles& particles, float radius,
                        SurfaceVelocityWorkspace& ws, std::vector<Vec3>& out) {
    out.resize(vertices.size());
    if (vertices.empty()) return;
    if (!(radius > 0.0f) || particles.active_count() == 0) {
        std::fill(out.begin(), out.end(), Vec3(0.0f));
        return;
    }
    ws.grid.build(particles.position, particles.active, radius);
    const float r2 = radius * radius, inv_r2 = 1.0f / r2;
    const Vec3* vel = particles.velocity.data();
    const auto order = ws.grid.order();
    const auto sx = ws.grid.sorted_x(), sy = ws.grid.sorted_y(), sz = ws.grid.sorted_z();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, vertices.size(), 512), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            const Vec3 x = vertices[i];
            Vec3 sum(0.0f);
            float weight = 0.0f;
            ws.grid.for_each_candidate_slot(x, [&](uint32_t k) {  // positions from the sorted copies
                const Vec3 d(x.x - sx[k], x.y - sy[k], x.z - sz[k]);
                const float d2 = glm::dot(d, d);
                if (d2 >= r2) return;  // hashed buckets and the 27 cells hold farther ones
                const float w = poly6(d2, inv_r2);
                sum += w * vel[order[k]];
                weight += w;
            });
            out[i] = normalised(sum, weight);
        }
    });
}

void surface_velocities_brute(std::span<const Vec3> vertices, const Particles& particles, float radius,
                              std::vector<Vec3>& out) {
    out.assign(vertices.size(), Vec3(0.0f));
    if (!(radius > 0.0f)) return;
    const float r2 = radius * radius, inv_r2 = 1.0f / r2;
    for (size_t i = 0; i < vertices.size(); ++i) {
        Vec3 sum(0.0f);
        float weight = 0.0f;
        for (size_t j = 0; j < particles.size(); ++j) {
            if (!particles.active[j]) continue;
            const Vec3 d = vertices[i] - particles.position[j];
            const float d2 = glm::dot(d, d);
            if (d2 >= r2) continue;
            const float w = poly6(d2, inv_r2);
            sum += w * particles.velocity[j];
            weight += w;
        }
        out[i] = normalised(sum, weight);
    }
}

}  // namespace mr::render
