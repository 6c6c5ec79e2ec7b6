// Particle stepping: the paper's section 2.3. Semi-implicit Euler (v += a dt;
// last = p; p += v dt), gravity plus springs, then terrain collision:
//  - paper mode (2.3.3): the AABB-tree leaf that holds the NEW position is searched,
//    the ray last -> new is tested against its triangles with eq. 4; on a hit the
//    velocity is reflected about the triangle normal and scaled by (1 - damping), and
//    the particle is placed at hit + offset up + v dt. A particle whose path crosses
//    a triangle of another leaf, or a seam the non-watertight test misses, falls
//    through: the paper's reported failure, kept here on purpose.
//  - robust mode: the swept segment is queried through the whole tree with the
//    watertight test (Woop et al. 2013), the bounce is re-checked along its own
//    segment, and a heightfield guard lifts any particle still below the mesh.
// Particles below the terrain box or outside its rectangle are re-spawned.
#include <metariver/particles.h>

#include <algorithm>
#include <cmath>

namespace mr {

std::string_view to_string(CollisionMode m) {
    switch (m) {
        case CollisionMode::Paper: return "paper";
        case CollisionMode::Robust: return "robust";
        case CollisionMode::None: return "none";
    }
    return "?";
}

ParticleSolver::ParticleSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn,
                               SpringDef springs, CollisionDef collision,
                               IntegratorDef integrator, uint32_t seed)
    : terrain_(terrain),
      bvh_(bvh),
      spawn_(spawn),
      springs_(springs),
      collision_(collision),
      integrator_(integrator),
      rng_(seed) {
    particles_.resize(static_cast<size_t>(std::max(spawn_.count, 0)));
    for (size_t i = 0; i < particles_.size(); ++i) {
        particles_.position[i] = spawn_.center;
        particles_.last_position[i] = spawn_.center;
    }
}

void ParticleSolver::spawn(size_t i) {
    const Vec3 lo = spawn_.center - spawn_.half_extent;
    const Vec3 hi = spawn_.center + spawn_.half_extent;
    Vec3 p;
    p.x = rng_.uniform(lo.x, hi.x);
    p.y = rng_.uniform(lo.y, hi.y);
    p.z = rng_.uniform(lo.z, hi.z);
    particles_.position[i] = p;
    particles_.last_position[i] = p;
    particles_.velocity[i] = spawn_.initial_velocity;
    particles_.active[i] = 1;
}

void ParticleSolver::pour(const Vec3& center, int count) {
    spawn_.center = center;
    const size_t n = particles_.size();
    if (n == 0) return;
    for (int k = 0; k < count; ++k) {
        if (next_to_activate_ < n) {
            spawn(next_to_activate_++);
        } else {
            spawn(next_to_pour_);
            next_to_pour_ = (next_to_pour_ + 1) % n;
        }
    }
}

void ParticleSolver::step_frame(float frame_dt) {
    const bool due = spawn_.interval == 0 || frame_ % static_cast<uint64_t>(spawn_.interval) == 0;
    if (due) {
        const size_t n = spawn_.interval == 0 ? particles_.size() : 1;
        for (size_t k = 0; k < n && next_to_activate_ < particles_.size(); ++k)
            spawn(next_to_activate_++);
    }
    const float dt = integrator_.fixed_dt > 0.0f ? integrator_.fixed_dt : frame_dt;
    const int sub = std::max(integrator_.substeps, 1);
    for (int s = 0; s < sub; ++s) step(dt / static_cast<float>(sub));
    ++frame_;
}

float ParticleSolver::depth_below_surface(const Vec3& p) const {
    if (!terrain_.contains_xz(p.x, p.z)) return 0.0f;
    return terrain_.height_mesh(p.x, p.z) - p.y;
}

bool ParticleSolver::out_of_bounds(const Vec3& p) const {
    return p.y < terrain_.bounds().min.y || !terrain_.contains_xz(p.x, p.z) || !std::isfinite(p.y);
}

void ParticleSolver::step(float dt) {
    Particles& p = particles_;
    const size_t n = p.size();
    const Vec3 g(0.0f, -integrator_.gravity, 0.0f);
    std::fill(p.force.begin(), p.force.end(), g);
    add_spring_forces_pairs(p, springs_);

    for (size_t i = 0; i < n; ++i) {
        if (!p.active[i]) continue;
        p.velocity[i] += p.force[i] * dt;
        p.last_position[i] = p.position[i];
        p.position[i] += p.velocity[i] * dt;
        ++counters_.particle_steps;
        collide(i, dt);
        if (out_of_bounds(p.position[i])) {
            ++counters_.respawned;
            spawn(i);
            continue;
        }
        if (depth_below_surface(p.position[i]) > kTunnelEpsilon) ++counters_.tunneled;
    }
}

void ParticleSolver::collide(size_t i, float dt) {
    switch (collision_.mode) {
        case CollisionMode::Paper: collide_paper(i, dt); break;
        case CollisionMode::Robust: collide_robust(i, dt); break;
        case CollisionMode::None: break;
    }
}

namespace {
Vec3 reflect_about(const Vec3& v, const Vec3& n) { return v - 2.0f * glm::dot(v, n) * n; }
}  // namespace

void ParticleSolver::collide_paper(size_t i, float dt) {
    Particles& p = particles_;
    const auto hit = bvh_.intersect_paper(terrain_, p.last_position[i], p.position[i]);
    if (!hit) return;
    ++counters_.collisions;
    const Vec3 v = reflect_about(p.velocity[i], hit->normal) * (1.0f - collision_.damping);
    p.velocity[i] = v;
    p.position[i] = hit->point + Vec3(0.0f, collision_.offset, 0.0f) + v * dt;
}

void ParticleSolver::collide_robust(size_t i, float dt) {
    Particles& p = particles_;
    Vec3 from = p.last_position[i];
    Vec3 to = p.position[i];
    Vec3 v = p.velocity[i];
    // A bounce moves the particle along a new segment (hit + offset -> + v dt) that can
    // itself cross the ground near a crease; re-check it a few times, then guard.
    constexpr int kMaxBounces = 4;
    for (int b = 0; b < kMaxBounces; ++b) {
        const auto hit = bvh_.intersect_segment(terrain_, from, to);
        if (!hit) break;
        ++counters_.collisions;
        v = reflect_about(v, hit->normal) * (1.0f - collision_.damping);
        // Straight up from a point on a heightfield never goes below it.
        from = hit->point + Vec3(0.0f, collision_.offset, 0.0f);
        to = from + v * dt;
    }
    // Heightfield guard: whatever the float rounding at seams did, never end below.
    if (terrain_.contains_xz(to.x, to.z)) {
        const float h = terrain_.height_mesh(to.x, to.z);
        if (to.y < h) {
            ++counters_.guarded;
            const Vec3 n = terrain_.normal_mesh(to.x, to.z);
            const float vn = glm::dot(v, n);
            if (vn < 0.0f) v -= vn * n;
            to.y = h + collision_.offset;
        }
    }
    p.velocity[i] = v;
    p.position[i] = to;
}

}  // namespace mr
