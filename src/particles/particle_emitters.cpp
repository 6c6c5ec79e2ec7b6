// The emitters of the own solvers and of the Bullet solver: where particles are born.
// The paper (section 2.3) activates one particle every spawn_interval frames at a
// random point of the spawn volume, and re-spawns particles that leave the terrain
// there. A flow rate makes each source owe rate x time particles, emitted from the
// inactive pool (never-spawned or recycled by a sink). PBF emits through lattice
// sources instead (LatticeSource: the rest spacing, never onto water). Every random
// draw of a run happens here, serially, in a fixed order: results do not depend on the
// thread count, and the three solvers draw the same points for the same seed.
#include <metariver/solver_parts.h>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr {

Emitters::Emitters(const Terrain& terrain, EmitterDef def, uint32_t seed)
    : terrain_(terrain), def_(std::move(def)), rng_(seed) {
    sources_.resize(source_count());
}

void Emitters::set_def(const EmitterDef& def) {
    def_ = def;
    sources_.resize(source_count());  // a removed source's debt goes with it
}

void Emitters::set_center(const Vec3& center) {
    def_.spawn.center = center;
    if (uses_lattice()) build_lattices();
}

std::pair<Vec3, Vec3> Emitters::volume(size_t k) const {
    if (k == 0) return {def_.spawn.center, def_.spawn.half_extent};
    const SourceDef& s = def_.spawn.sources[k - 1];
    return {s.center, s.half_extent};
}

float Emitters::asked_rate(size_t k) const {
    return k == 0 ? def_.spawn.particles_per_second() : def_.spawn.particles_per_second(k - 1);
}

const LatticeSource* Emitters::lattice_source(size_t k) const {
    return k < sources_.size() && sources_[k].lattice ? &*sources_[k].lattice : nullptr;
}

float Emitters::emit_rate(size_t k) const {
    if (k >= source_count()) return 0.0f;
    const float rate = asked_rate(k);
    const LatticeSource* l = lattice_source(k);
    return l ? std::min(rate, l->max_rate()) : rate;
}

void Emitters::spawn(ParticlePool& pool, size_t i, size_t k) {
    const auto [center, half] = volume(k);
    const Vec3 lo = center - half;
    const Vec3 hi = center + half;
    Vec3 p = center;
    if (def_.spawn.shape == SourceShape::Box) {
        p.x = rng_.uniform(lo.x, hi.x);
        p.y = rng_.uniform(lo.y, hi.y);
        p.z = rng_.uniform(lo.z, hi.z);
    } else if (def_.spawn.shape == SourceShape::Disc) {
        // Uniform in the disc: radius sqrt(u) R, angle 2 pi v.
        const float r = std::sqrt(rng_.uniform(0.0f, 1.0f)) * half.x;
        const float a = rng_.uniform(0.0f, 6.2831853f);
        p.x += r * std::cos(a);
        p.z += r * std::sin(a);
        p.y = rng_.uniform(lo.y, hi.y);
    }
    // A source volume that dips into the terrain (an automatic source on a slope, a box
    // drawn through a hill) must not place water in the ground: where the drawn point
    // is under the (lifted) mesh it starts on it. Before this the springs valley counted
    // 18 tunneled in 600 frames, every one a particle born 1 m underground. (Bullet: a
    // sphere drawn less than a radius above the ground starts a radius above it; an
    // engine would push it out.)
    if (def_.on_ground && terrain_.contains_xz(p.x, p.z))
        p.y = std::max(p.y, terrain_.height_mesh(p.x, p.z) + def_.ground_lift + def_.ground_offset);
    pool.activate(i, p, def_.spawn.initial_velocity);
}

void Emitters::activate_due(ParticlePool& pool) {
    const int interval = def_.spawn.interval;
    if (interval != 0 && pool.frame % static_cast<uint64_t>(interval) != 0) return;
    const size_t n = interval == 0 ? pool.size() : 1;
    for (size_t k = 0; k < n && pool.next_to_activate < pool.size(); ++k) spawn(pool, pool.next_to_activate++);
}

void Emitters::place(ParticlePool& pool, std::span<const Vec3> positions, std::span<const Vec3> velocities) {
    for (size_t k = 0; k < positions.size(); ++k) {
        if (pool.next_to_activate >= pool.size()) break;
        pool.activate(pool.next_to_activate++, positions[k], k < velocities.size() ? velocities[k] : def_.spawn.initial_velocity);
    }
}

void Emitters::pour(ParticlePool& pool, const Vec3& center, int count) {
    set_center(center);
    const size_t n = pool.size();
    if (n == 0 || count <= 0) return;
    if (uses_lattice()) {
        // The lattice source emits them as slots free up; when the pool is short, the
        // oldest-poured particles are taken back into it first.
        for (int k = 0; k < count && size_t(k) < n; ++k) {
            if (size_t(k) >= pool.free()) {
                const size_t i = pool.slot_of_id(pool.next_to_pour);
                if (i < pool.next_to_activate) pool.deactivate(i);
                pool.next_to_pour = static_cast<uint32_t>((pool.next_to_pour + 1) % n);
            }
        }
        sources_[0].credit += double(std::min<size_t>(size_t(count), n));
        return;
    }
    for (int k = 0; k < count; ++k) {
        if (pool.next_to_activate < n) {
            spawn(pool, pool.next_to_activate++);  // inactive particles are the suffix
        } else {
            spawn(pool, pool.slot_of_id(pool.next_to_pour));
            pool.next_to_pour = static_cast<uint32_t>((pool.next_to_pour + 1) % n);
        }
    }
}

void Emitters::begin_frame(ParticlePool& pool) {
    if (!uses_lattice()) {
        if (!by_rate()) activate_due(pool);
        return;
    }
    // PBF: every activation goes through the lattice source. Without a rate the (main)
    // source owes the whole pool (interval 0) or one particle when due; what does not
    // fit now is emitted as the slots free up.
    const int interval = def_.spawn.interval;
    const bool due = interval == 0 || pool.frame % static_cast<uint64_t>(interval) == 0;
    double& credit = sources_[0].credit;
    if (!by_rate() && interval == 0) credit = std::max(credit, double(pool.free()));
    else if (!by_rate() && due) credit += 1.0;
    if (pool.frame == 0) emit_lattice(pool, 0);
}

void Emitters::after_step(ParticlePool& pool, float h) {
    if (uses_lattice()) {
        for (size_t k = 0; k < sources_.size(); ++k) {
            if (by_rate()) sources_[k].credit += double(emit_rate(k)) * h;
            emit_lattice(pool, k);
        }
    } else if (by_rate()) {
        emit(pool, h);
    }
}

void Emitters::emit(ParticlePool& pool, float dt) {
    // Each source owes rate * dt particles; whole ones come from the inactive pool
    // (never-spawned or recycled by a sink). An empty pool drops the debt: the budget
    // caps the flow. The sources take their turns in order within a step.
    for (size_t k = 0; k < sources_.size(); ++k) {
        double& credit = sources_[k].credit;
        credit += double(asked_rate(k)) * dt;
        while (credit >= 1.0) {
            credit -= 1.0;
            if (pool.next_to_activate >= pool.size()) {
                credit = std::min(credit, 1.0);
                break;
            }
            spawn(pool, pool.next_to_activate++, k);
            ++pool.counters.emitted;
        }
    }
}

void Emitters::emit_lattice(ParticlePool& pool, size_t k) {
    LatticeSource& lattice = *sources_[k].lattice;
    double& credit = sources_[k].credit;
    const double cap = double(std::max<size_t>(lattice.slots().size(), 1));
    if (credit > cap) credit = cap;  // a blocked source does not build an endless backlog
    const size_t want = std::min(pool.free(), static_cast<size_t>(std::max(credit, 0.0)));
    if (want == 0) return;
    lattice.emit(pool.particles.position, pool.next_to_activate, want, slots_);
    for (const Vec3& q : slots_) {
        pool.activate(pool.next_to_activate++, q, def_.spawn.initial_velocity);
        ++pool.counters.emitted;
    }
    credit -= double(slots_.size());
}

void Emitters::build_lattices() {
    sources_.resize(source_count());
    for (size_t k = 0; k < sources_.size(); ++k) {
        const auto [center, half] = volume(k);
        LatticeSource::Def d{.shape = def_.spawn.shape,
                             .center = center,
                             .half_extent = half,
                             .inflow = def_.spawn.initial_velocity,
                             .spacing = def_.lattice_spacing,
                             .clearance = def_.on_ground ? def_.ground_lift + def_.ground_offset : 0.0f,
                             .gravity = def_.gravity,
                             .follow_ground = def_.spawn.follow_ground && by_rate()};
        sources_[k].lattice = LatticeSource::build(d, terrain_);
    }
}

std::vector<std::string> Emitters::warnings() const {
    std::vector<std::string> w;
    if (!uses_lattice()) return w;
    for (size_t k = 0; k < sources_.size(); ++k) {
        const LatticeSource& l = *sources_[k].lattice;
        const auto [c, half] = volume(k);
        const float rate = asked_rate(k);
        const std::string centre = source_key(k, SourceField::Center), extent = source_key(k, SourceField::HalfExtent),
                          flow = source_key(k, SourceField::FlowRate);
        if (l.slots().empty())
            w.push_back(fmt::format("{}: the source volume at [{}, {}, {}] has no lattice slot above the terrain "
                                    "(spacing pbf.spacing = {} m): it cannot emit; raise the source or widen {}",
                                    centre, c.x, c.y, c.z, def_.lattice_spacing, extent));
        else if (rate > l.max_rate())
            w.push_back(fmt::format("{}: {:.1f} particles per second is more than the source can deliver "
                                    "at spacing {} m and inflow speed {:.2f} m/s ({} lattice slots): capped to {:.1f}; "
                                    "widen {} or raise particles.initial_velocity",
                                    flow, rate, def_.lattice_spacing, glm::length(def_.spawn.initial_velocity),
                                    l.slots().size(), l.max_rate(), extent));
    }
    return w;
}

}  // namespace mr
