// The particle pool (active prefix, activation, deactivation, push) and the neighbour
// grid's cell ordering: every array sorted by cell for locality, the stable id kept
// (SPlisHSPlasH's performNeighborhoodSearchSort).
#include <metariver/solver_parts.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace mr {

ParticlePool::ParticlePool(size_t n, const Vec3& at) {
    particles.resize(n);
    for (size_t i = 0; i < n; ++i) {
        particles.position[i] = at;
        particles.last_position[i] = at;
    }
}

void ParticlePool::activate(size_t i, const Vec3& x, const Vec3& v) {
    particles.position[i] = x;
    particles.last_position[i] = x;
    particles.velocity[i] = v;
    particles.active[i] = 1;
    particles.birth_frame[i] = static_cast<uint32_t>(frame);
    if (slots) slots->reset(i);
}

void ParticlePool::deactivate(size_t i) {
    Particles& p = particles;
    const size_t j = --next_to_activate;  // the last active particle takes slot i
    if (i != j) {
        std::swap(p.position[i], p.position[j]);
        std::swap(p.last_position[i], p.last_position[j]);
        std::swap(p.velocity[i], p.velocity[j]);
        std::swap(p.force[i], p.force[j]);
        std::swap(p.id[i], p.id[j]);
        std::swap(p.birth_frame[i], p.birth_frame[j]);
        if (slots) slots->swap(i, j);
    }
    p.active[j] = 0;
}

size_t ParticlePool::slot_of_id(uint32_t id) const {
    const auto& ids = particles.id;
    if (id < ids.size() && ids[id] == id) return id;  // nothing reordered it
    return static_cast<size_t>(std::find(ids.begin(), ids.end(), id) - ids.begin());
}

size_t ParticlePool::push(const Vec3& center, float radius, const Vec3& velocity) {
    if (!(radius > 0.0f) || !std::isfinite(radius)) return 0;
    const float r2 = radius * radius;
    size_t pushed = 0;
    Particles& p = particles;
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        const Vec3 d = p.position[i] - center;
        const float q = glm::dot(d, d) / r2;
        if (q >= 1.0f) continue;
        p.velocity[i] += velocity * ((1.0f - q) * (1.0f - q));
        if (slots) slots->reset(i);  // awake: its next step is not undone
        ++pushed;
    }
    return pushed;
}

void ParticlePool::record_max_speed() {
    // The largest squared speed, then one square root: the same float as the largest
    // glm::length (sqrt is correctly rounded and never decreasing), for any split.
    const auto& v = particles.velocity;
    const auto block = [&](const tbb::blocked_range<size_t>& r, float m) {
        for (size_t i = r.begin(); i != r.end(); ++i) m = std::max(m, glm::dot(v[i], v[i]));
        return m;
    };
    constexpr size_t kGrain = 8192;  // one block (a few thousand particles) runs here, without a task
    const float v2max = next_to_activate <= kGrain
                            ? block(tbb::blocked_range<size_t>(0, next_to_activate, kGrain), 0.0f)
                            : tbb::parallel_reduce(tbb::blocked_range<size_t>(0, next_to_activate, kGrain), 0.0f, block,
                                                   [](float a, float b) { return std::max(a, b); });
    counters.max_speed = std::sqrt(v2max);
}

void SortedGrid::sort(ParticlePool& pool, float cell) {
    Particles& p = pool.particles;
    // The active prefix only: the idle slots past it are neither binned nor moved.
    const size_t n = std::min(pool.active(), p.size());
    grid_.build(std::span<const Vec3>(p.position).first(n), std::span<const uint8_t>(p.active).first(n),
                std::max(cell, 1e-3f));
    // New order: binned (active) particles by cell (all of the prefix), the rest unchanged.
    const auto order = grid_.order();
    perm_.assign(order.begin(), order.end());
    for (size_t i = order.size(); i < n; ++i) perm_.push_back(static_cast<uint32_t>(i));
    auto permute = [&](auto& v, auto& scratch) {
        scratch.resize(n);
        for (size_t k = 0; k < n; ++k) scratch[k] = v[perm_[k]];
        std::copy_n(scratch.begin(), n, v.begin());
    };
    permute(p.position, scratch_vec_);
    permute(p.last_position, scratch_vec_);
    permute(p.velocity, scratch_vec_);
    // Not p.force: every step that reads it writes it first, after this sort (springs fill
    // it with gravity; PBF does not use it).
    permute(p.id, scratch_id_);
    permute(p.birth_frame, scratch_id_);  // same scratch: no allocation
    if (pool.slots) pool.slots->permute(perm_);
    // active stays a prefix of the same length: nothing to move.
    grid_.relabel_identity();
}

}  // namespace mr
