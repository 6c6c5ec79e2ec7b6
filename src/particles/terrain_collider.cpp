// Terrain collision, the paper's section 2.3.3 and its robust twin, under one response
// policy per solver (ContactResponse):
//  - paper (2.3.3): the AABB-tree leaf that holds the NEW position is searched, the ray
//    last -> new is tested against its triangles with eq. 4; on a hit the velocity is
//    reflected about the triangle normal and scaled by (1 - damping), and the particle
//    is placed at hit + offset up + v dt. A particle whose path crosses a triangle of
//    another leaf, or a seam the non-watertight test misses, falls through: the paper's
//    reported failure, kept here on purpose.
//  - robust: the swept segment is queried through the whole tree (or by walking the
//    heightfield's cells: same hits) with the watertight test (Woop et al. 2013); the
//    response (a bounce, or the fluid's slide along the ground) is re-checked along its
//    own segment, and a heightfield guard lifts any particle still below the mesh.
// One contact loop serves the bounce and the slide; collide_active runs it over every
// active particle in parallel (each touches only its own slot: deterministic).
#include <metariver/solver_parts.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "parallel_blocks.h"

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

ContactResponse contact_response(CollisionMode mode, bool fluid) {
    if (mode == CollisionMode::None) return ContactResponse::None;
    if (fluid) return ContactResponse::Slide;
    return mode == CollisionMode::Paper ? ContactResponse::Paper : ContactResponse::Bounce;
}

TerrainCollider::TerrainCollider(const Terrain& terrain, const Bvh& bvh, CollisionDef def, bool fluid)
    : terrain_(terrain), bvh_(bvh), fluid_(fluid) {
    set_def(def);
}

void TerrainCollider::set_def(const CollisionDef& def) {
    def_ = def;
    response_ = contact_response(def.mode, fluid_);
}

ContactCounts TerrainCollider::collide_active(Particles& p, float dt, size_t count) const {
    std::atomic<uint64_t> steps{0}, collisions{0}, guarded{0}, tunneled{0};
    // Blocks of 128: a swept query costs ~0.1 us, so a few hundred particles (the hybrid's)
    // still spread over the threads.
    const size_t n = std::min(count, p.size());
    parallel_pass(tbb::blocked_range<size_t>(0, n, 128), n, [&](const tbb::blocked_range<size_t>& range) {
        ContactCounts c;
        for (size_t i = range.begin(); i != range.end(); ++i) {
            if (!p.active[i]) continue;
            ++c.steps;
            collide(p, i, dt, c);  // counts tunneled before any correction
        }
        steps += c.steps;
        collisions += c.collisions;
        guarded += c.guarded;
        tunneled += c.tunneled;
    });
    return ContactCounts{.steps = steps, .collisions = collisions, .guarded = guarded, .tunneled = tunneled};
}

void TerrainCollider::collide(Particles& p, size_t i, float dt, ContactCounts& c) const {
    switch (response_) {
        case ContactResponse::Paper: collide_paper(p, i, dt, c); break;
        case ContactResponse::Bounce:
        case ContactResponse::Slide: sweep(p, i, dt, c); return;  // counts inside, before its guard
        case ContactResponse::None: break;
    }
    if (ends_below(p.position[i] - Vec3(0.0f, def_.radius, 0.0f))) ++c.tunneled;
}

bool TerrainCollider::ends_below(const Vec3& lifted) const {
    return terrain_.contains_xz(lifted.x, lifted.z) && lifted.y < terrain_.height_mesh(lifted.x, lifted.z);
}

namespace {
Vec3 reflect_about(const Vec3& v, const Vec3& n) { return v - 2.0f * glm::dot(v, n) * n; }
}  // namespace

void TerrainCollider::collide_paper(Particles& p, size_t i, float dt, ContactCounts& c) const {
    const Vec3 lift(0.0f, def_.radius, 0.0f);
    const auto hit = bvh_.intersect_paper(terrain_, p.last_position[i] - lift, p.position[i] - lift);
    if (!hit) return;
    ++c.collisions;
    const Vec3 v = reflect_about(p.velocity[i], hit->normal) * (1.0f - def_.damping);
    p.velocity[i] = v;
    p.position[i] = hit->point + lift + Vec3(0.0f, def_.offset, 0.0f) + v * dt;
}

// Contact skin: the query runs from a hair above the segment's start to a hair below
// its end. A particle resting exactly on the surface (or a rounding error under it)
// starts its next segment on the plane, where the watertight test's t = 0 can round
// either way, and a segment ending exactly on the surface has the same problem at
// t = 1: both are contacts. On a heightfield a vertical shift of the start can only
// reveal crossings, never hide one. The skin grows with the height's magnitude (float
// spacing is 6e-8 relative).
std::optional<RayHit> TerrainCollider::robust_hit(const Vec3& from, const Vec3& to) const {
    const float skin = 1e-4f + 1e-6f * std::max(std::abs(from.y), std::abs(to.y));
    const Vec3 a = from + Vec3(0.0f, skin, 0.0f);
    const Vec3 b = to - Vec3(0.0f, skin, 0.0f);
    if (def_.query == CollisionQuery::Heightfield) {
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
void TerrainCollider::count_and_guard(Vec3& to, Vec3& v, ContactCounts& c) const {
    if (!ends_below(to)) return;
    ++c.tunneled;
    ++c.guarded;
    const float h = terrain_.height_mesh(to.x, to.z);
    const Vec3 n = terrain_.normal_mesh(to.x, to.z);
    const float vn = glm::dot(v, n);
    if (vn < 0.0f) v -= vn * n;
    to.y = h + def_.offset;
}

// The contact loop. A response moves the particle along a new segment from hit +
// offset that can itself cross the ground near a crease: it is re-checked a few
// times, then the particle stays at its last contact, and the guard has the last word.
//  - bounce: the velocity reflected about the normal and damped; the new segment is v dt;
//  - slide (the fluid): the rest of the motion and the velocity lose their part into
//    the ground and the damping share; the new segment is the damped rest.
void TerrainCollider::sweep(Particles& p, size_t i, float dt, ContactCounts& c) const {
    const Vec3 lift(0.0f, def_.radius, 0.0f);
    Vec3 from = p.last_position[i] - lift;
    Vec3 to = p.position[i] - lift;
    Vec3 v = p.velocity[i];
    const float keep = 1.0f - def_.damping;
    constexpr int kMaxContacts = 4;
    for (int b = 0; b <= kMaxContacts; ++b) {
        const auto hit = robust_hit(from, to);
        if (!hit) break;
        ++c.collisions;
        if (b == kMaxContacts) {  // still bouncing or sliding into a crease: stay at the last contact
            to = from;
            break;
        }
        const Vec3 n = hit->normal;
        // Straight up from a point on a heightfield never goes below it.
        const Vec3 above = hit->point + Vec3(0.0f, def_.offset, 0.0f);
        if (response_ == ContactResponse::Slide) {
            Vec3 rest = to - hit->point;
            rest -= std::min(glm::dot(rest, n), 0.0f) * n;
            const float vn = glm::dot(v, n);
            if (vn < 0.0f) v -= vn * n;
            v *= keep;
            from = above;
            to = from + rest * keep;
        } else {
            v = reflect_about(v, n) * keep;
            from = above;
            to = from + v * dt;
        }
    }
    count_and_guard(to, v, c);
    p.velocity[i] = v;
    p.position[i] = to + lift;
}

// Out of the ground along the triangle's normal onto its plane lifted by radius +
// offset (a vertical lift on a steep wall would fling the particle up by the wall's
// height). The offset keeps resting particles strictly above the surface, so the
// next step's swept segment starts above it and rounding cannot hide a crossing. At a
// concave crease the new point can be under the neighbouring triangle: a few rounds,
// then the particle stays where it started the step (`fallback`, above the ground): a
// vertical lift out of a narrow pit or off a spike's flank would fling it. After a
// push, a point still on the triangle it was pushed out of and within half the offset
// of its target counts as out: on a plane the push lands exactly on the target, and
// float rounding lands it a hair below half the time; without the slack three such
// rounds sent a particle sliding down a steep face back to `fallback` every few steps,
// and it stuck to the wall. The slack is for that rounding only: a push along a steep
// wall's normal that lands on the floor at the wall's foot leaves the point up to the
// slack under the floor's plane, and accepting it there kept particles in the crease
// bobbing by the slack every few steps, never at rest (the box basin of
// tests/scene/sound_water_test.cpp); the floor's own push follows instead.
bool TerrainCollider::push_out(Vec3& x, const Vec3& fallback) const {
    const float lift = def_.radius + def_.offset;
    const float slack = 0.5f * def_.offset;
    constexpr uint32_t kNone = ~0u;
    uint32_t pushed_off = kNone;  // the triangle of the last push
    const auto tolerance = [&](const Vec3& p) {
        return pushed_off != kNone && terrain_.triangle_at(p.x, p.z) == pushed_off ? slack : 0.0f;
    };
    for (int round = 0; round < 3; ++round) {
        if (!terrain_.contains_xz(x.x, x.z)) return pushed_off != kNone;
        const float h = terrain_.height_mesh(x.x, x.z) + lift;
        if (x.y >= h - tolerance(x)) return pushed_off != kNone;
        // Deeper under the ground than the step moved it: it did not sink through the
        // surface it was on, it ran into a cliff face between two samples. Lifting it
        // onto the ground above would launch it up the cliff (tens of m/s): it stops at
        // the face. In every round, not only the first: a push off the face's steep
        // triangle (a small lift) can land under the terrace above, whose push then
        // lifted the whole cliff's height at once (0.48 m in a 1/120 s step: 45 m/s).
        const uint32_t tri = terrain_.triangle_at(x.x, x.z);
        const Vec3 nrm = terrain_.triangle_normal(tri);
        if ((h - x.y) * nrm.y > glm::length(x - fallback) + lift) {
            x = fallback;
            return true;
        }
        x += ((h - x.y) * nrm.y) * nrm;
        pushed_off = tri;
    }
    if (terrain_.contains_xz(x.x, x.z) && x.y < terrain_.height_mesh(x.x, x.z) + lift - tolerance(x)) x = fallback;
    return true;
}

}  // namespace mr
