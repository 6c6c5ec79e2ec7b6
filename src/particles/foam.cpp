// Diffuse spray, foam and bubbles: Ihmsen, Akinci, Akinci and Teschner, "Unified
// spray, foam and air bubbles for particle-based fluids", The Visual Computer 28(6),
// 2012. The potentials, the mapping and the advection are described in
// include/metariver/foam.h; the thresholds' scaling in docs/scene-format.md ([foam]).
#include <metariver/foam.h>

#include "grid_runs.h"
#include "pbf_simd.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace mr {

namespace {

/// Counter-based random numbers: the same (frame, id, draw) gives the same value
/// whatever thread asks (splitmix64's finaliser).
uint64_t mix(uint64_t x) {
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}
/// Uniform in [0, 1) from 24 bits (exact in float).
float uniform(uint64_t frame, uint32_t id, uint32_t draw) {
    const uint64_t h = mix(frame * 0x100000001B3ull ^ mix((uint64_t(id) << 32) | draw));
    return float(h >> 40) * (1.0f / 16777216.0f);
}

/// |sum_j x^_ij W~| below which a particle has no surface normal: a full lattice
/// neighbourhood (about 32 particles within h = 2 spacings) sums to ~0, a flat free
/// surface's half neighbourhood to ~3; irregular interiors stay under 1.
constexpr float kSurfaceNormalMin = 1.0f;

float phi(float i, float lo, float hi) { return (std::min(i, hi) - std::min(i, lo)) / (hi - lo); }

/// A particle's surface normal from its sum of x^_ij W~: a lone pair or a thin sheet still
/// gets a direction; a full neighbourhood sums to (near) zero and has no surface.
Vec3 surface_normal(const Vec3& sum) {
    const float len = glm::length(sum);
    return len > kSurfaceNormalMin ? sum / len : Vec3(0.0f);
}

/// The wave-crest potential from the convex curvature sum: only where the particle moves
/// along its normal.
float crest_potential(const Vec3& v, float speed, const Vec3& n, float curv) {
    return speed > 1e-6f && glm::dot(v / speed, n) >= 0.6f ? curv : 0.0f;
}

/// For every binned fluid particle i, in parallel over the grid's cell runs: calls
/// f(i, each), where each(g) calls g(j, x^_ij, W~(r_ij)) for every neighbour j != i
/// within h in a fixed order. Positions come from the grid's sorted copies and each
/// cell run's neighbour ranges are gathered once for all its particles (grid_runs.h).
template <class F>
void for_each_fluid(const NeighborGrid& grid, float h, F&& f) {
    const auto order = grid.order();
    const auto sx = grid.sorted_x(), sy = grid.sorted_y(), sz = grid.sorted_z();
    const float h2 = h * h;
    for_each_run(grid, [&](uint32_t k, const Ranges& rg) {
        const float xi = sx[k], yi = sy[k], zi = sz[k];
        auto each = [&](auto&& g) {
            for (int q = 0; q < rg.n; ++q)
                for (uint32_t m = rg.s[q]; m < rg.e[q]; ++m) {
                    if (m == k) continue;
                    const Vec3 d(xi - sx[m], yi - sy[m], zi - sz[m]);
                    const float r2 = glm::dot(d, d);
                    if (r2 >= h2 || r2 <= 1e-12f) continue;
                    const float rr = std::sqrt(r2);
                    g(order[m], d / rr, 1.0f - rr / h);
                }
        };
        f(order[k], each);
    });
}

/// Two unit vectors normal to d (unit) and to each other.
void basis(const Vec3& d, Vec3& e1, Vec3& e2) {
    const Vec3 a = std::abs(d.x) < 0.9f ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    e1 = glm::normalize(glm::cross(d, a));
    e2 = glm::cross(d, e1);
}

/// The classification's view of the fluid in the grid's order: its sorted positions and,
/// in `sorted` (3 m floats, m binned particles, filled by potentials_simd), the velocity's
/// x, y, z.
pbf_simd::FoamArrays sorted_arrays(const NeighborGrid& g, std::vector<float>& sorted) {
    const size_t m = g.order().size();
    sorted.resize(3 * m);
    float* const v = sorted.data();
    return {g.sorted_x().data(), g.sorted_y().data(), g.sorted_z().data(), v, v + m, v + 2 * m};
}

}  // namespace

FoamSystem::FoamSystem(const FoamDef& def, float kernel_radius, float gravity)
    : def_(def), h_(kernel_radius), gravity_(gravity) {
    // The cap bounds the diffuse arrays: reserved once, no allocation in the frame loop.
    const size_t cap = size_t(std::max(def.max_particles, 0));
    each_array([&](auto& v) { v.reserve(cap); });
    keep_.reserve(cap);
}

DiffuseKind FoamSystem::classify(int neighbours, const FoamDef& def) {
    if (neighbours < def.spray_neighbours) return DiffuseKind::Spray;
    if (neighbours > def.bubble_neighbours) return DiffuseKind::Bubble;
    return DiffuseKind::Foam;
}

void FoamSystem::step(const Particles& fluid, const Terrain& terrain, float dt, uint64_t frame) {
    stats_.generated = stats_.expired = stats_.left = stats_.handed_over = 0;
    grid_.build(fluid.position, fluid.active, h_);
    advect(terrain, dt);
    potentials(fluid);
    emit(fluid, dt, frame);
    classify_all(fluid);
    stats_.spray = stats_.foam = stats_.bubbles = 0;
    for (const uint8_t k : p_.kind) {
        stats_.spray += k == uint8_t(DiffuseKind::Spray);
        stats_.foam += k == uint8_t(DiffuseKind::Foam);
        stats_.bubbles += k == uint8_t(DiffuseKind::Bubble);
    }
}

void FoamSystem::advect(const Terrain& terrain, float dt) {
    const size_t n = p_.size();
    keep_.assign(n, 0);
    const Aabb b = terrain.bounds();
    const Vec3 g(0.0f, -gravity_, 0.0f);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            Vec3& x = p_.position[i];
            Vec3& v = p_.velocity[i];
            // Kind and averaged fluid velocity from the end of the previous step (one
            // neighbour gather per particle and step: classify_all).
            const DiffuseKind kind = DiffuseKind(p_.kind[i]);
            const Vec3 vf = p_.neighbours[i] > 0 ? p_.fluid_velocity[i] : v;
            switch (kind) {
                case DiffuseKind::Spray: v += g * dt; break;
                case DiffuseKind::Foam: v = vf; break;
                case DiffuseKind::Bubble: v += -def_.buoyancy * g * dt + def_.drag * (vf - v); break;
            }
            x += v * dt;
            p_.life[i] -= dt;
            uint8_t keep = 1;
            if (p_.life[i] <= 0.0f) keep = 0;
            else if (x.x < b.min.x || x.x > b.max.x || x.z < b.min.z || x.z > b.max.z) keep = 2;
            else {
                const float ground = terrain.height_mesh(x.x, x.z);
                if (x.y < ground) {
                    if (kind == DiffuseKind::Spray) keep = 2;
                    else {
                        x.y = ground;
                        v.y = std::max(v.y, 0.0f);
                    }
                }
            }
            keep_[i] = keep;
        }
    });
    // Stable serial compaction: the survivors keep their order.
    size_t out = 0;
    for (size_t i = 0; i < n; ++i) {
        if (keep_[i] != 1) {
            (keep_[i] == 0 ? stats_.expired : stats_.left) += 1;
            continue;
        }
        if (out != i) {
            p_.position[out] = p_.position[i];
            p_.velocity[out] = p_.velocity[i];
            p_.life[out] = p_.life[i];
        }
        ++out;
    }
    resize(out);
}

size_t FoamSystem::hand_over(const std::function<bool(const Vec3&)>& leave, DiffuseParticles& out) {
    size_t kept = 0;
    const size_t n = p_.size();
    for (size_t i = 0; i < n; ++i) {
        const bool go = leave(p_.position[i]);
        DiffuseParticles& to = go ? out : p_;
        const size_t at = go ? out.size() : kept++;
        const auto put = [&](auto& into, const auto& from) {
            if (go) into.push_back(from[i]);
            else into[at] = from[i];
        };
        put(to.position, p_.position), put(to.velocity, p_.velocity), put(to.life, p_.life);
        put(to.kind, p_.kind), put(to.neighbours, p_.neighbours), put(to.fluid_velocity, p_.fluid_velocity);
        if (!go) continue;
        const DiffuseKind k = DiffuseKind(p_.kind[i]);
        (k == DiffuseKind::Spray ? stats_.spray : k == DiffuseKind::Foam ? stats_.foam : stats_.bubbles) -= 1;
    }
    resize(kept);
    stats_.handed_over = n - kept;
    return n - kept;
}

void FoamSystem::resize(size_t n) {
    each_array([&](auto& v) { v.resize(n); });
}

void FoamSystem::classify_all(const Particles& fluid) {
    const float h = h_, h2 = h * h;
    // The fluid's positions from the grid's sorted copies (grid_ was built this step, on
    // these positions): contiguous per cell.
    const auto order = grid_.order();
    const auto sx = grid_.sorted_x(), sy = grid_.sorted_y(), sz = grid_.sorted_z();
    // With SIMD, eight candidates at a time over the cell-ordered velocities that
    // potentials_simd gathered this step (the same fluid, the same grid).
    const bool simd = simd_ && pbf_simd::available();
    const pbf_simd::FoamArrays a = simd ? sorted_arrays(grid_, sorted_) : pbf_simd::FoamArrays{};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, p_.size(), 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            const Vec3 x = p_.position[i];
            int count = 0;
            float wsum = 0.0f;
            Vec3 vsum(0.0f);
            if (simd) {
                grid_.for_each_candidate_range(x, [&](uint32_t b, uint32_t e) {
                    pbf_simd::foam_classify_sums(a, x, b, e, h, count, wsum, vsum);
                });
            } else {
                grid_.for_each_candidate_slot(x, [&](uint32_t k) {
                    const Vec3 d(x.x - sx[k], x.y - sy[k], x.z - sz[k]);
                    const float r2 = glm::dot(d, d);
                    if (r2 >= h2) return;
                    const float w = 1.0f - std::sqrt(r2) / h;  // W~, the paper's weighting
                    ++count;
                    wsum += w;
                    vsum += w * fluid.velocity[order[k]];
                });
            }
            p_.kind[i] = uint8_t(classify(count, def_));
            p_.neighbours[i] = uint16_t(std::min(count, 65535));
            p_.fluid_velocity[i] = wsum > 0.0f ? vsum / wsum : Vec3(0.0f);
        }
    });
}

void FoamSystem::potentials(const Particles& fluid) {
    const size_t n = fluid.size();
    ta_.assign(n, 0.0f);
    wc_.assign(n, 0.0f);
    ek_.assign(n, 0.0f);
    const float h = h_;
    if (simd_ && pbf_simd::available()) {
        potentials_simd(fluid);  // its normals in the grid's order (sorted_nrm_)
        return;
    }
    normal_.assign(n, Vec3(0.0f));
    // Pass 1: surface normals n_i = sum_j x_ij W~ (zero where the neighbourhood is full).
    for_each_fluid(grid_, h, [&](uint32_t i, auto&& each) {
        Vec3 s(0.0f);
        each([&](uint32_t, const Vec3& xh, float w) { s += xh * w; });
        normal_[i] = surface_normal(s);
    });
    // Pass 2: the three potentials.
    for_each_fluid(grid_, h, [&](uint32_t i, auto&& each) {
        const Vec3 vi = fluid.velocity[i], ni = normal_[i];
        const float speed = glm::length(vi);
        ek_[i] = 0.5f * speed * speed;
        // Below energy_min a particle emits nothing (Phi_k = 0): its other two
        // potentials are left at 0 unread, which spares slow water the gather.
        if (ek_[i] <= def_.energy_min) return;
        float ta = 0.0f, curv = 0.0f;
        each([&](uint32_t j, const Vec3& xh, float w) {
            const Vec3 vij = vi - fluid.velocity[j];
            const float vl = glm::length(vij);
            if (vl > 1e-6f) ta += vl * (1.0f - glm::dot(vij / vl, xh)) * w;
            // Convex only: the neighbour lies behind i along i's normal (x^_ji . n_i < 0).
            if (glm::dot(-xh, ni) < 0.0f) curv += (1.0f - glm::dot(ni, normal_[j])) * w;
        });
        ta_[i] = ta;
        wc_[i] = crest_potential(vi, speed, ni, curv);
    });
}

void FoamSystem::potentials_simd(const Particles& fluid) {
    // The same two passes eight list entries at a time (pbf_simd.h), over the fluid's
    // neighbour lists within h (NeighborLists, built here on the grid's cell-ordered
    // positions: each pass reads only the pairs, where a scan of the 27 cells' ranges read
    // about six candidates per pair) and cell-ordered copies of the positions, the
    // velocities and the first pass's normals. The classification's SoA velocities are
    // filled on the way.
    const auto order = grid_.order();
    const size_t m = order.size();
    const uint32_t count = static_cast<uint32_t>(m);
    const float h = h_;
    sorted_arrays(grid_, sorted_);
    float* const v = sorted_.data();
    const auto sx = grid_.sorted_x(), sy = grid_.sorted_y(), sz = grid_.sorted_z();
    sorted_pos_.resize(m);
    sorted_vel_.resize(m);
    sorted_nrm_.resize(m);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const Vec3 u = fluid.velocity[order[k]];
            v[k] = u.x, v[m + k] = u.y, v[2 * m + k] = u.z;
            sorted_vel_[k] = u;
            sorted_pos_[k] = Vec3(sx[k], sy[k], sz[k]);
        }
    });
    lists_.build(grid_, sorted_pos_, h);
    const uint32_t* index = lists_.index();
    const Vec3* pos = sorted_pos_.data();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const uint32_t kk = static_cast<uint32_t>(k);
            const Vec3 nk = surface_normal(pbf_simd::foam_normal_sum(pos, count, kk, index, lists_.first(kk),
                                                                     lists_.first(kk + 1), h));
            sorted_nrm_[k] = nk;
        }
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, m, 256), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t k = r.begin(); k != r.end(); ++k) {
            const uint32_t kk = static_cast<uint32_t>(k), i = order[k];
            const Vec3 vi = sorted_vel_[k], ni = sorted_nrm_[k];
            const float speed = glm::length(vi);
            ek_[i] = 0.5f * speed * speed;
            if (ek_[i] <= def_.energy_min) continue;
            float ta = 0.0f, curv = 0.0f;
            pbf_simd::foam_potential_sums(pos, sorted_vel_.data(), sorted_nrm_.data(), count, kk, vi, ni, index,
                                          lists_.first(kk), lists_.first(kk + 1), h, ta, curv);
            ta_[i] = ta;
            wc_[i] = crest_potential(vi, speed, ni, curv);
        }
    });
}

void FoamSystem::emit(const Particles& fluid, float dt, uint64_t frame) {
    const size_t n = fluid.size();
    emit_count_.assign(n, 0);
    const FoamDef& d = def_;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            if (!fluid.active[i]) continue;
            const float k = phi(ek_[i], d.energy_min, d.energy_max);
            if (k <= 0.0f) continue;
            const float rate = k * (d.trapped_air_rate * phi(ta_[i], d.trapped_air_min, d.trapped_air_max) +
                                    d.wave_crest_rate * phi(wc_[i], d.wave_crest_min, d.wave_crest_max));
            const float expected = rate * dt;
            const float whole = std::floor(expected);
            const uint32_t extra = uniform(frame, fluid.id[i], 0) < expected - whole ? 1u : 0u;
            emit_count_[i] = uint32_t(std::min(whole, 1e6f)) + extra;
        }
    });
    // Serial prefix sum in fluid index order; the cap cuts the tail.
    const size_t live = p_.size();
    const size_t room = size_t(std::max(d.max_particles, 0)) > live ? size_t(d.max_particles) - live : 0;
    emit_first_.resize(n);
    size_t total = 0;
    uint64_t asked = 0;
    for (size_t i = 0; i < n; ++i) {
        asked += emit_count_[i];
        const uint32_t c = uint32_t(std::min<size_t>(emit_count_[i], room - total));
        emit_count_[i] = c;
        emit_first_[i] = uint32_t(total);
        total += c;
    }
    stats_.generated = total;
    stats_.generated_total += total;
    stats_.capped_total += asked - total;
    if (total == 0) return;
    resize(live + total);
    const float radius = 0.5f * h_;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
            const uint32_t c = emit_count_[i];
            if (c == 0) continue;
            const Vec3 xi = fluid.position[i], vi = fluid.velocity[i];
            const float speed = glm::length(vi);
            const Vec3 dir = speed > 1e-6f ? vi / speed : Vec3(0, 1, 0);
            Vec3 e1, e2;
            basis(dir, e1, e2);
            for (uint32_t k = 0; k < c; ++k) {
                const uint32_t id = fluid.id[i];
                const float u = uniform(frame, id, 1 + 4 * k), a = uniform(frame, id, 2 + 4 * k);
                const float s = uniform(frame, id, 3 + 4 * k), l = uniform(frame, id, 4 + 4 * k);
                const float rr = radius * std::sqrt(u), th = 6.28318531f * a;
                const Vec3 off = rr * (std::cos(th) * e1 + std::sin(th) * e2);
                const size_t o = live + emit_first_[i] + k;
                p_.position[o] = xi + off + dir * (s * speed * dt);
                p_.velocity[o] = vi;
                p_.life[o] = d.lifetime_min + l * (d.lifetime_max - d.lifetime_min);
            }
        }
    });
}

uint64_t FoamSystem::state_hash() const {
    uint64_t h = 1469598103934665603ull;
    auto feed = [&](const void* data, size_t bytes) {
        const auto* b = static_cast<const unsigned char*>(data);
        for (size_t k = 0; k < bytes; ++k) {
            h ^= b[k];
            h *= 1099511628211ull;
        }
    };
    feed(p_.position.data(), p_.position.size() * sizeof(Vec3));
    feed(p_.velocity.data(), p_.velocity.size() * sizeof(Vec3));
    feed(p_.life.data(), p_.life.size() * sizeof(float));
    feed(p_.kind.data(), p_.kind.size());
    return h;
}

}  // namespace mr
