// Foam seeded from a heightfield's velocity (heightfield_foam.h).
#include "heightfield_foam.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace mr {

namespace {

constexpr float kWetDepth = 0.05f;       // metres: shallower water carries no foam
constexpr float kLift = 0.03f;           // metres above the surface (drawn on it)
constexpr float kRateSpacing = 0.5f;     // the spacing the [foam] rates are per particle of

/// A uniform draw in [0, 1) from (frame, cell, draw): a 64-bit xorshift-multiply hash.
float draw01(uint64_t frame, uint64_t cell, uint32_t k) {
    uint64_t z = (frame * 0xD1B54A32D192ED03ull) ^ (cell * 0x9E3779B97F4A7C15ull) ^ (uint64_t(k) << 56);
    z ^= z >> 33;
    z *= 0xFF51AFD7ED558CCDull;
    z ^= z >> 33;
    z *= 0xC4CEB9FE1A85EC53ull;
    z ^= z >> 33;
    return float(z >> 40) * (1.0f / 16777216.0f);
}

float ramp(float v, float lo, float hi) { return hi > lo ? std::clamp((v - lo) / (hi - lo), 0.0f, 1.0f) : 0.0f; }

/// Bilinear read of the grid at (x, z) metres: depth, level (bed + depth) and velocity.
struct Sample {
    float depth = 0.0f, level = 0.0f;
    Vec3 velocity{0.0f};
    bool inside = false;
};

Sample sample(const HeightfieldWater& w, std::span<const Vec3> bed, float x, float z) {
    const float u = (x - w.origin.x) / w.spacing, v = (z - w.origin.z) / w.spacing;
    Sample s;
    if (!(u >= 0.0f && v >= 0.0f && u <= float(w.columns - 1) && v <= float(w.rows - 1))) return s;
    const int j = std::min(int(u), w.columns - 2), i = std::min(int(v), w.rows - 2);
    const float fu = u - float(j), fv = v - float(i);
    const float wt[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
    const size_t c = size_t(i) * size_t(w.columns) + size_t(j);
    const size_t k[4] = {c, c + 1, c + size_t(w.columns), c + size_t(w.columns) + 1};
    for (int q = 0; q < 4; ++q) {
        s.depth += wt[q] * w.depth[k[q]];
        s.level += wt[q] * (bed[k[q]].y + w.depth[k[q]]);
        s.velocity += wt[q] * w.velocity[k[q]];
    }
    s.inside = true;
    return s;
}

}  // namespace

float HeightfieldFoam::emission_rate(const HeightfieldWater& w, std::span<const Vec3> bed, int i, int j) const {
    if (i < 1 || j < 1 || i + 1 >= w.rows || j + 1 >= w.columns) return 0.0f;
    const size_t k = size_t(i) * size_t(w.columns) + size_t(j), cols = size_t(w.columns);
    if (w.depth[k] < kWetDepth || w.velocity.size() != w.size()) return 0.0f;
    const Vec3 v = w.velocity[k];
    const float phi_k = ramp(0.5f * glm::dot(v, v), def_.energy_min, def_.energy_max);
    if (phi_k <= 0.0f) return 0.0f;
    // The flow converging on the cell's neighbours (a jump; not the shear at the banks).
    float ta = 0.0f;
    const std::pair<size_t, Vec3> around[4] = {{k - 1, Vec3(-1, 0, 0)}, {k + 1, Vec3(1, 0, 0)},
                                               {k - cols, Vec3(0, 0, -1)}, {k + cols, Vec3(0, 0, 1)}};
    for (const auto& [n, e] : around)
        if (w.depth[n] >= kWetDepth) ta += std::max(glm::dot(v - w.velocity[n], e), 0.0f);
    const auto level = [&](size_t n) { return bed[n].y + w.depth[n]; };
    const float gx = (level(k + 1) - level(k - 1)) / (2.0f * w.spacing);
    const float gz = (level(k + cols) - level(k - cols)) / (2.0f * w.spacing);
    const float wc = std::sqrt(gx * gx + gz * gz);
    const float per_particle = phi_k * (def_.trapped_air_rate * ramp(ta, def_.trapped_air_min, def_.trapped_air_max) +
                                        def_.wave_crest_rate * ramp(wc, def_.wave_crest_min, def_.wave_crest_max));
    return per_particle * (w.spacing / kRateSpacing);  // a cell's surface row of particles
}

void HeightfieldFoam::step(const HeightfieldWater& w, std::span<const Vec3> bed, float dt, uint64_t frame) {
    if (w.rows < 2 || w.columns < 2 || bed.size() != w.size() || w.depth.size() != w.size() || !(dt > 0.0f)) return;
    advect(w, bed, dt);
    emit(w, bed, dt, frame);
}

void HeightfieldFoam::advect(const HeightfieldWater& w, std::span<const Vec3> bed, float dt) {
    size_t kept = 0;
    for (size_t n = 0; n < p_.size(); ++n) {
        Vec3 p = p_.position[n];
        const Sample here = sample(w, bed, p.x, p.z);
        p += dt * Vec3(here.velocity.x, 0.0f, here.velocity.z);
        const Sample there = sample(w, bed, p.x, p.z);
        const float life = p_.life[n] - dt;
        if (life <= 0.0f || !there.inside || there.depth < kWetDepth) continue;
        p.y = there.level + kLift;
        p_.position[kept] = p;
        p_.velocity[kept] = there.velocity;
        p_.fluid_velocity[kept] = there.velocity;
        p_.life[kept] = life;
        p_.kind[kept] = uint8_t(DiffuseKind::Foam);
        p_.neighbours[kept] = 0;
        ++kept;
    }
    p_.position.resize(kept);
    p_.velocity.resize(kept);
    p_.fluid_velocity.resize(kept);
    p_.life.resize(kept);
    p_.kind.resize(kept);
    p_.neighbours.resize(kept);
}

void HeightfieldFoam::push(const Vec3& position, const Vec3& velocity, float life) {
    p_.position.push_back(position);
    p_.velocity.push_back(velocity);
    p_.fluid_velocity.push_back(velocity);
    p_.life.push_back(life);
    p_.kind.push_back(uint8_t(DiffuseKind::Foam));
    p_.neighbours.push_back(0);
}

size_t HeightfieldFoam::take_landed(FoamSystem& from, const HeightfieldWater& w, std::span<const Vec3> bed) {
    if (w.rows < 2 || w.columns < 2 || bed.size() != w.size() || w.depth.size() != w.size()) return 0;
    landed_ = DiffuseParticles{};
    const size_t n = from.hand_over(
        [&](const Vec3& p) {
            const Sample s = sample(w, bed, p.x, p.z);
            return s.inside && s.depth >= kWetDepth && p.y < s.level;
        },
        landed_);
    const size_t cap = size_t(std::max(def_.max_particles, 0));
    for (size_t i = 0; i < n && p_.size() < cap; ++i) {
        const Vec3 p = landed_.position[i];
        const Sample s = sample(w, bed, p.x, p.z);
        push(Vec3(p.x, s.level + kLift, p.z), s.velocity, landed_.life[i]);
        ++landed_total_;
    }
    return n;
}

void HeightfieldFoam::emit(const HeightfieldWater& w, std::span<const Vec3> bed, float dt, uint64_t frame) {
    const size_t cap = size_t(std::max(def_.max_particles, 0));
    for (int i = 1; i + 1 < w.rows; ++i) {
        const auto [lo, hi] = w.wet_columns(i);  // dry cells emit nothing
        for (int j = std::max(lo, 1); j <= std::min(hi, w.columns - 2); ++j) {
            const float rate = emission_rate(w, bed, i, j);
            if (rate <= 0.0f) continue;
            const uint64_t cell = uint64_t(i) * uint64_t(w.columns) + uint64_t(j);
            const float expected = rate * dt;
            const int count = int(expected) + (draw01(frame, cell, 0) < expected - std::floor(expected) ? 1 : 0);
            for (int q = 0; q < count && p_.size() < cap; ++q) {
                const float x = bed[cell].x + (draw01(frame, cell, 3 * q + 1) - 0.5f) * w.spacing;
                const float z = bed[cell].z + (draw01(frame, cell, 3 * q + 2) - 0.5f) * w.spacing;
                const Sample s = sample(w, bed, x, z);
                if (!s.inside || s.depth < kWetDepth) continue;
                const float life = def_.lifetime_min + (def_.lifetime_max - def_.lifetime_min) * draw01(frame, cell, 3 * q + 3);
                push(Vec3(x, s.level + kLift, z), s.velocity, life);
                ++generated_total_;
            }
        }
    }
}

}  // namespace mr
