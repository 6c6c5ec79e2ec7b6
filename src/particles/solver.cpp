// Particle stepping: the paper's section 2.3. Semi-implicit Euler (v += a dt;
// last = p; p += v dt), gravity plus springs, then terrain collision:
//  - paper mode (2.3.3): the AABB-tree leaf that holds the NEW position is searched,
//    the ray last -> new is tested against its triangles with eq. 4; on a hit the
//    velocity is reflected about the triangle normal and scaled by (1 - damping), and
//    the particle is placed at hit + offset up + v dt. A particle whose path crosses
//    a triangle of another leaf, or a seam the non-watertight test misses, falls
//    through: the paper's reported failure, kept here on purpose.
//  - robust mode: the swept segment is queried through the whole tree (or by walking
//    the heightfield's cells: same hits) with the watertight test (Woop et al. 2013),
//    the bounce is re-checked along its own segment, and a heightfield guard lifts any
//    particle still below the mesh.
// Particles below the terrain box or outside its rectangle are re-spawned.
//
// Parallel and deterministic: forces are per-particle gathers, integration and
// collision are independent per particle (tbb::parallel_for), and everything that
// draws random numbers (activation, respawn) runs serially in index order afterwards,
// so results do not depend on the thread count.
#include <metariver/particles.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <fmt/format.h>

#include <algorithm>
#include <atomic>
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

std::string_view to_string(CollisionQuery q) {
    switch (q) {
        case CollisionQuery::Tree: return "tree";
        case CollisionQuery::Heightfield: return "heightfield";
    }
    return "?";
}

ParticleSolver::ParticleSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn, CollisionDef collision,
                               IntegratorDef integrator, uint32_t seed, SinkDef sink, float lattice_spacing)
    : terrain_(terrain),
      bvh_(bvh),
      spawn_(spawn),
      collision_(collision),
      integrator_(integrator),
      rng_(seed),
      sink_(sink),
      lattice_spacing_(lattice_spacing) {
    const size_t n = static_cast<size_t>(std::max(spawn_.count, 0));
    particles_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        particles_.position[i] = spawn_.center;
        particles_.last_position[i] = spawn_.center;
        particles_.id[i] = static_cast<uint32_t>(i);
    }
    respawn_flag_.assign(n, 0);
    emitters_.resize(1 + spawn_.sources.size());
}

SpringSolver::SpringSolver(const Terrain& terrain, const Bvh& bvh, SpawnDef spawn, SpringDef springs,
                           CollisionDef collision, IntegratorDef integrator, uint32_t seed, SinkDef sink)
    : ParticleSolver(terrain, bvh, spawn, collision, integrator, seed, sink, 0.0f), springs_(springs) {}

std::pair<Vec3, Vec3> ParticleSolver::source_volume(size_t k) const {
    if (k == 0) return {spawn_.center, spawn_.half_extent};
    const SourceDef& s = spawn_.sources[k - 1];
    return {s.center, s.half_extent};
}

const LatticeSource* ParticleSolver::lattice_source(size_t k) const {
    return k < emitters_.size() && emitters_[k].lattice ? &*emitters_[k].lattice : nullptr;
}

void ParticleSolver::spawn(size_t i) { spawn(i, 0); }

void ParticleSolver::spawn(size_t i, size_t k) {
    const auto [center, half] = source_volume(k);
    const Vec3 lo = center - half;
    const Vec3 hi = center + half;
    Vec3 p = center;
    if (spawn_.shape == SourceShape::Box) {
        p.x = rng_.uniform(lo.x, hi.x);
        p.y = rng_.uniform(lo.y, hi.y);
        p.z = rng_.uniform(lo.z, hi.z);
    } else if (spawn_.shape == SourceShape::Disc) {
        // Uniform in the disc: radius sqrt(u) R, angle 2 pi v.
        const float r = std::sqrt(rng_.uniform(0.0f, 1.0f)) * half.x;
        const float a = rng_.uniform(0.0f, 6.2831853f);
        p.x += r * std::cos(a);
        p.z += r * std::sin(a);
        p.y = rng_.uniform(lo.y, hi.y);
    }
    // A source volume that dips into the terrain (an automatic source on a slope, a box
    // drawn through a hill) must not place water in the ground: where the drawn point
    // is under the (radius-lifted) mesh it starts on it. Before this the springs valley
    // counted 18 tunneled in 600 frames, every one a particle born 1 m underground.
    if (collision_.mode != CollisionMode::None && terrain_.contains_xz(p.x, p.z))
        p.y = std::max(p.y, terrain_.height_mesh(p.x, p.z) + collision_.radius + collision_.offset);
    particles_.position[i] = p;
    particles_.last_position[i] = p;
    particles_.velocity[i] = spawn_.initial_velocity;
    particles_.active[i] = 1;
    particles_.birth_frame[i] = static_cast<uint32_t>(frame_);
    reset_slot(i);
}

size_t ParticleSolver::slot_of_id(uint32_t id) const {
    const auto& ids = particles_.id;
    if (id < ids.size() && ids[id] == id) return id;  // nothing reordered it
    return static_cast<size_t>(std::find(ids.begin(), ids.end(), id) - ids.begin());
}

void ParticleSolver::place(std::span<const Vec3> positions) { place(positions, {}); }

void ParticleSolver::place(std::span<const Vec3> positions, std::span<const Vec3> velocities) {
    for (size_t k = 0; k < positions.size(); ++k) {
        if (next_to_activate_ >= particles_.size()) break;
        const Vec3& q = positions[k];
        const size_t i = next_to_activate_++;
        particles_.position[i] = q;
        particles_.last_position[i] = q;
        particles_.velocity[i] = k < velocities.size() ? velocities[k] : spawn_.initial_velocity;
        particles_.active[i] = 1;
        particles_.birth_frame[i] = static_cast<uint32_t>(frame_);
        reset_slot(i);
    }
}

bool ParticleSolver::set_shared(const SpawnDef& spawn, const CollisionDef& collision, const IntegratorDef& integrator,
                                const SinkDef& sink, float lattice_spacing) {
    if (spawn.count != spawn_.count) return false;
    spawn_ = spawn;
    collision_ = collision;
    integrator_ = integrator;
    sink_ = sink;
    lattice_spacing_ = lattice_spacing;
    emitters_.resize(1 + spawn_.sources.size());  // a removed source's debt goes with it
    return true;
}

bool SpringSolver::set_params(const SpawnDef& spawn, const SpringDef& springs, const CollisionDef& collision,
                              const IntegratorDef& integrator, const SinkDef& sink) {
    if (!set_shared(spawn, collision, integrator, sink, 0.0f)) return false;
    springs_ = springs;
    return true;
}

void ParticleSolver::set_spawn_center(const Vec3& center) {
    spawn_.center = center;
    if (uses_lattice()) build_lattice();
}

size_t ParticleSolver::push(const Vec3& center, float radius, const Vec3& velocity) {
    if (!(radius > 0.0f) || !std::isfinite(radius)) return 0;
    const float r2 = radius * radius;
    size_t pushed = 0;
    for (size_t i = 0; i < particles_.size(); ++i) {
        if (!particles_.active[i]) continue;
        const Vec3 d = particles_.position[i] - center;
        const float q = glm::dot(d, d) / r2;
        if (q >= 1.0f) continue;
        particles_.velocity[i] += velocity * ((1.0f - q) * (1.0f - q));
        reset_slot(i);  // awake: its next step is not undone
        ++pushed;
    }
    return pushed;
}

void ParticleSolver::pour(const Vec3& center, int count) {
    set_spawn_center(center);
    const size_t n = particles_.size();
    if (n == 0 || count <= 0) return;
    if (uses_lattice()) {
        // The lattice source emits them as slots free up; when the pool is short, the
        // oldest-poured particles are taken back into it first.
        for (int k = 0; k < count && size_t(k) < n; ++k) {
            if (size_t(k) >= n - next_to_activate_) {
                const size_t i = slot_of_id(next_to_pour_);
                if (i < next_to_activate_) deactivate(i);
                next_to_pour_ = static_cast<uint32_t>((next_to_pour_ + 1) % n);
            }
        }
        emitters_[0].credit += double(std::min<size_t>(size_t(count), n));
        return;
    }
    for (int k = 0; k < count; ++k) {
        if (next_to_activate_ < n) {
            spawn(next_to_activate_++);  // inactive particles are the suffix
        } else {
            spawn(slot_of_id(next_to_pour_));
            next_to_pour_ = static_cast<uint32_t>((next_to_pour_ + 1) % n);
        }
    }
}

void ParticleSolver::deactivate(size_t i) {
    Particles& p = particles_;
    const size_t j = --next_to_activate_;  // the last active particle takes slot i
    if (i != j) {
        std::swap(p.position[i], p.position[j]);
        std::swap(p.last_position[i], p.last_position[j]);
        std::swap(p.velocity[i], p.velocity[j]);
        std::swap(p.force[i], p.force[j]);
        std::swap(p.id[i], p.id[j]);
        std::swap(p.birth_frame[i], p.birth_frame[j]);
        swap_slots(i, j);
    }
    p.active[j] = 0;
}

void ParticleSolver::emit(float dt) {
    // Each source owes rate * dt particles; whole ones come from the inactive pool
    // (never-spawned or recycled by a sink). An empty pool drops the debt: the budget
    // caps the flow. The sources take their turns in order within a step.
    for (size_t k = 0; k < emitters_.size(); ++k) {
        double& credit = emitters_[k].credit;
        credit += double(asked_rate(k)) * dt;
        while (credit >= 1.0) {
            credit -= 1.0;
            if (next_to_activate_ >= particles_.size()) {
                credit = std::min(credit, 1.0);
                break;
            }
            spawn(next_to_activate_++, k);
            ++counters_.emitted;
        }
    }
}

float ParticleSolver::emit_rate(size_t k) const {
    if (k >= source_count()) return 0.0f;
    const float rate = asked_rate(k);
    const LatticeSource* l = lattice_source(k);
    return l ? std::min(rate, l->max_rate()) : rate;
}

void ParticleSolver::build_lattice() {
    emitters_.resize(source_count());
    for (size_t k = 0; k < emitters_.size(); ++k) {
        const auto [center, half] = source_volume(k);
        LatticeSource::Def d{.shape = spawn_.shape,
                             .center = center,
                             .half_extent = half,
                             .inflow = spawn_.initial_velocity,
                             .spacing = lattice_spacing_,
                             .clearance = collision_.mode == CollisionMode::None ? 0.0f : collision_.radius + collision_.offset,
                             .gravity = integrator_.gravity,
                             .follow_ground = spawn_.follow_ground && by_rate()};
        emitters_[k].lattice = LatticeSource::build(d, terrain_);
    }
}

std::vector<std::string> ParticleSolver::warnings() const {
    std::vector<std::string> w;
    if (!uses_lattice()) return w;
    for (size_t k = 0; k < emitters_.size(); ++k) {
        const LatticeSource& l = *emitters_[k].lattice;
        const auto [c, half] = source_volume(k);
        const float rate = asked_rate(k);
        const std::string centre = source_key(k, SourceField::Center), extent = source_key(k, SourceField::HalfExtent),
                          flow = source_key(k, SourceField::FlowRate);
        if (l.slots().empty())
            w.push_back(fmt::format("{}: the source volume at [{}, {}, {}] has no lattice slot above the terrain "
                                    "(spacing pbf.spacing = {} m): it cannot emit; raise the source or widen {}",
                                    centre, c.x, c.y, c.z, lattice_spacing_, extent));
        else if (rate > l.max_rate())
            w.push_back(fmt::format("{}: {:.1f} particles per second is more than the source can deliver "
                                    "at spacing {} m and inflow speed {:.2f} m/s ({} lattice slots): capped to {:.1f}; "
                                    "widen {} or raise particles.initial_velocity",
                                    flow, rate, lattice_spacing_, glm::length(spawn_.initial_velocity), l.slots().size(),
                                    l.max_rate(), extent));
    }
    return w;
}

void ParticleSolver::emit_lattice(size_t k) {
    LatticeSource& lattice = *emitters_[k].lattice;
    double& credit = emitters_[k].credit;
    const size_t pool = particles_.size() - next_to_activate_;
    const double cap = double(std::max<size_t>(lattice.slots().size(), 1));
    if (credit > cap) credit = cap;  // a blocked source does not build an endless backlog
    const size_t want = std::min(pool, static_cast<size_t>(std::max(credit, 0.0)));
    if (want == 0) return;
    lattice.emit(particles_.position, next_to_activate_, want, emit_slots_);
    for (const Vec3& q : emit_slots_) {
        const size_t i = next_to_activate_++;
        particles_.position[i] = q;
        particles_.last_position[i] = q;
        particles_.velocity[i] = spawn_.initial_velocity;
        particles_.active[i] = 1;
        particles_.birth_frame[i] = static_cast<uint32_t>(frame_);
        reset_slot(i);
        ++counters_.emitted;
    }
    credit -= double(emit_slots_.size());
}

void ParticleSolver::step_frame(float frame_dt) {
    exits_.clear();
    const bool by_rate = this->by_rate();
    const bool due = spawn_.interval == 0 || frame_ % static_cast<uint64_t>(spawn_.interval) == 0;
    if (uses_lattice()) {
        // PBF: every activation goes through the lattice source. Without a rate the
        // (main) source owes the whole pool (interval 0) or one particle when due; what
        // does not fit now is emitted as the slots free up.
        const size_t pool = particles_.size() - next_to_activate_;
        double& credit = emitters_[0].credit;
        if (!by_rate && spawn_.interval == 0) credit = std::max(credit, double(pool));
        else if (!by_rate && due) credit += 1.0;
        if (frame_ == 0) emit_lattice(0);
    } else if (due && !by_rate) {
        const size_t n = spawn_.interval == 0 ? particles_.size() : 1;
        for (size_t k = 0; k < n && next_to_activate_ < particles_.size(); ++k) spawn(next_to_activate_++);
    }
    const float dt = integrator_.fixed_dt > 0.0f ? integrator_.fixed_dt : frame_dt;
    const int sub = std::max(integrator_.substeps, 1);
    const float h = dt / static_cast<float>(sub);
    for (int s = 0; s < sub; ++s) {
        // Emit after the step: particles a sink took out this step are back at once
        // when the rate allows, so the budget stays in the river.
        step(h);
        if (uses_lattice()) {
            for (size_t k = 0; k < emitters_.size(); ++k) {
                if (by_rate) emitters_[k].credit += double(emit_rate(k)) * h;
                emit_lattice(k);
            }
        } else if (by_rate) {
            emit(h);
        }
    }
    ++frame_;
}

bool ParticleSolver::out_of_bounds(const Vec3& p) const {
    return p.y < terrain_.bounds().min.y || !terrain_.contains_xz(p.x, p.z) || !std::isfinite(p.y);
}

uint8_t ParticleSolver::exit_flag(const Vec3& p) const {
    if (sink_.in_a_box(p)) return 2;
    if (!out_of_bounds(p)) return 0;
    // Over an edge (not through the bottom): an outlet.
    if (sink_.kind == SinkKind::Edges && std::isfinite(p.y) && p.y >= terrain_.bounds().min.y &&
        std::isfinite(p.x) && std::isfinite(p.z))
        return 3;
    return 1;
}

void ParticleSolver::finish_step(uint64_t steps, const StepCounts& c) {
    counters_.particle_steps += steps;
    counters_.collisions += c.collisions;
    counters_.guarded += c.guarded;
    counters_.tunneled += c.tunneled;
    const size_t n = particles_.size();
    if (uses_lattice()) {
        // PBF: out of bounds or sunk, every particle goes back to the pool; without a
        // flow rate the source owes it back at once (it re-emits as slots free up).
        const bool by_rate = this->by_rate();
        for (size_t i = n; i-- > 0;) {
            if (respawn_flag_[i] == 0) continue;
            if (respawn_flag_[i] == 1) ++counters_.respawned;
            else record_sunk(i, respawn_flag_[i] == 3);
            deactivate(i);
            if (!by_rate) emitters_[0].credit += 1.0;
        }
        record_max_speed();
        return;
    }
    const bool pool = by_rate();
    // Serial, in index order: the RNG sequence does not depend on the thread count.
    for (size_t i = 0; i < n; ++i) {
        if (respawn_flag_[i] == 1) {
            ++counters_.respawned;
            spawn(i);
        } else if (respawn_flag_[i] >= 2 && !pool) {
            record_sunk(i, respawn_flag_[i] == 3);  // no flow rate: straight back to the source
            spawn(i);
        }
    }
    if (pool) {  // recycled into the pool, highest index first (swaps only move processed slots)
        for (size_t i = n; i-- > 0;)
            if (respawn_flag_[i] >= 2) {
                record_sunk(i, respawn_flag_[i] == 3);
                deactivate(i);
            }
    }
    record_max_speed();
}

void ParticleSolver::record_sunk(size_t i, bool over_an_edge) {
    ++counters_.sunk;
    if (over_an_edge) exits_.push_back(particles_.position[i]);
}

void ParticleSolver::record_max_speed() {
    // The largest squared speed, then one square root: the same float as the largest
    // glm::length (sqrt is correctly rounded and never decreasing), for any split.
    const auto& v = particles_.velocity;
    const float v2max = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, next_to_activate_, 8192), 0.0f,
        [&](const tbb::blocked_range<size_t>& r, float m) {
            for (size_t i = r.begin(); i != r.end(); ++i) m = std::max(m, glm::dot(v[i], v[i]));
            return m;
        },
        [](float a, float b) { return std::max(a, b); });
    counters_.max_speed = std::sqrt(v2max);
}

void ParticleSolver::sort_by_cell(float cell) {
    Particles& p = particles_;
    const size_t n = p.size();
    grid_.build(p.position, p.active, std::max(cell, 1e-3f));
    // New order: binned (active) particles by cell, then the inactive suffix unchanged.
    const auto order = grid_.order();
    perm_.assign(order.begin(), order.end());
    for (size_t i = order.size(); i < n; ++i) perm_.push_back(static_cast<uint32_t>(i));
    auto permute = [&](std::vector<Vec3>& v) {
        scratch_vec_.resize(n);
        for (size_t k = 0; k < n; ++k) scratch_vec_[k] = v[perm_[k]];
        v.swap(scratch_vec_);
    };
    permute(p.position);
    permute(p.last_position);
    permute(p.velocity);
    // Not p.force: every step that reads it writes it first, after this sort (springs fill
    // it with gravity; PBF does not use it).
    scratch_id_.resize(n);
    for (size_t k = 0; k < n; ++k) scratch_id_[k] = p.id[perm_[k]];
    p.id.swap(scratch_id_);
    for (size_t k = 0; k < n; ++k) scratch_id_[k] = p.birth_frame[perm_[k]];  // same scratch: no allocation
    p.birth_frame.swap(scratch_id_);
    permute_slots(perm_);
    // active stays a prefix of the same length: nothing to move.
    grid_.relabel_identity();
}

void SpringSolver::step(float dt) {
    Particles& p = particles_;
    const size_t n = p.size();
    const bool grid_springs = springs_.mode == SpringMode::Grid;
    if (grid_springs) sort_by_cell(spring_reach(springs_));

    const Vec3 g(0.0f, -integrator_.gravity, 0.0f);
    std::fill(p.force.begin(), p.force.end(), g);
    if (springs_.stiffness != 0.0f) {
        if (grid_springs)
            add_spring_forces_grid(p, grid_, springs_);
        else
            add_spring_forces_pairs(p, springs_);
    }

    std::atomic<uint64_t> steps{0}, collisions{0}, guarded{0}, tunneled{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 512), [&](const tbb::blocked_range<size_t>& range) {
        StepCounts c;
        uint64_t local_steps = 0;
        for (size_t i = range.begin(); i != range.end(); ++i) {
            respawn_flag_[i] = 0;
            if (!p.active[i]) continue;
            p.velocity[i] += p.force[i] * dt;
            p.last_position[i] = p.position[i];
            p.position[i] += p.velocity[i] * dt;
            ++local_steps;
            collide(i, dt, c);  // counts tunneled before any correction
            respawn_flag_[i] = exit_flag(p.position[i]);
        }
        steps += local_steps;
        collisions += c.collisions;
        guarded += c.guarded;
        tunneled += c.tunneled;
    });
    finish_step(steps, StepCounts{.collisions = collisions, .guarded = guarded, .tunneled = tunneled});
}

void ParticleSolver::collide(size_t i, float dt, StepCounts& c) {
    switch (collision_.mode) {
        case CollisionMode::Paper:
            collide_paper(i, dt, c);
            break;
        case CollisionMode::Robust: collide_robust(i, dt, c); return;  // counts inside, before its guard
        case CollisionMode::None: break;
    }
    if (ends_below_terrain(particles_.position[i] - Vec3(0.0f, collision_.radius, 0.0f))) ++c.tunneled;
}

bool ParticleSolver::ends_below_terrain(const Vec3& lifted) const {
    return terrain_.contains_xz(lifted.x, lifted.z) && lifted.y < terrain_.height_mesh(lifted.x, lifted.z);
}

namespace {
Vec3 reflect_about(const Vec3& v, const Vec3& n) { return v - 2.0f * glm::dot(v, n) * n; }
}  // namespace

// Collisions run on the particle's centre moved down by its radius, i.e. against the
// terrain lifted by the radius.
void ParticleSolver::collide_paper(size_t i, float dt, StepCounts& c) {
    Particles& p = particles_;
    const Vec3 lift(0.0f, collision_.radius, 0.0f);
    const auto hit = bvh_.intersect_paper(terrain_, p.last_position[i] - lift, p.position[i] - lift);
    if (!hit) return;
    ++c.collisions;
    const Vec3 v = reflect_about(p.velocity[i], hit->normal) * (1.0f - collision_.damping);
    p.velocity[i] = v;
    p.position[i] = hit->point + lift + Vec3(0.0f, collision_.offset, 0.0f) + v * dt;
}

// Contact skin: the query runs from a hair above the segment's start to a hair below
// its end. A particle resting exactly on the surface (or a rounding error under it)
// starts its next segment on the plane, where the watertight test's t = 0 can round
// either way, and a segment ending exactly on the surface has the same problem at
// t = 1: both are contacts. On a heightfield a vertical shift of the start can only
// reveal crossings, never hide one. The skin grows with the height's magnitude (float
// spacing is 6e-8 relative).
std::optional<RayHit> ParticleSolver::robust_hit(const Vec3& from, const Vec3& to) const {
    const float skin = 1e-4f + 1e-6f * std::max(std::abs(from.y), std::abs(to.y));
    const Vec3 a = from + Vec3(0.0f, skin, 0.0f);
    const Vec3 b = to - Vec3(0.0f, skin, 0.0f);
    if (collision_.query == CollisionQuery::Heightfield) {
        HeightfieldQuery q = intersect_segment_heightfield(terrain_, a, b);
        if (!q.too_long) return q.hit;
    }
    return bvh_.intersect_segment(terrain_, a, b);
}

// Measure, then correct. A particle-step that ends below the (lifted) mesh after the
// collision response is a tunneling event: the swept query missed a crossing or the
// response left the particle below. It is counted first; the heightfield guard then
// lifts the particle to the surface (+ offset), removes its velocity into the ground,
// and counts itself. With a sound query and response both counters stay 0 (tests).
void ParticleSolver::count_and_guard(Vec3& to, Vec3& v, StepCounts& c) const {
    if (!ends_below_terrain(to)) return;
    ++c.tunneled;
    ++c.guarded;
    const float h = terrain_.height_mesh(to.x, to.z);
    const Vec3 n = terrain_.normal_mesh(to.x, to.z);
    const float vn = glm::dot(v, n);
    if (vn < 0.0f) v -= vn * n;
    to.y = h + collision_.offset;
}

void ParticleSolver::collide_robust(size_t i, float dt, StepCounts& c) {
    Particles& p = particles_;
    const Vec3 lift(0.0f, collision_.radius, 0.0f);
    Vec3 from = p.last_position[i] - lift;
    Vec3 to = p.position[i] - lift;
    Vec3 v = p.velocity[i];
    // A bounce moves the particle along a new segment (hit + offset -> + v dt) that can
    // itself cross the ground near a crease; re-check it a few times, then guard.
    constexpr int kMaxBounces = 4;
    for (int b = 0; b <= kMaxBounces; ++b) {
        const auto hit = robust_hit(from, to);
        if (!hit) break;
        ++c.collisions;
        if (b == kMaxBounces) {  // still bouncing in a crease: stay at the last contact
            to = from;
            break;
        }
        v = reflect_about(v, hit->normal) * (1.0f - collision_.damping);
        // Straight up from a point on a heightfield never goes below it.
        from = hit->point + Vec3(0.0f, collision_.offset, 0.0f);
        to = from + v * dt;
    }
    count_and_guard(to, v, c);
    p.velocity[i] = v;
    p.position[i] = to + lift;
}

}  // namespace mr
