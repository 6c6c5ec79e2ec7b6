// Rigid bodies on a heightfield's water (rigid_bodies_grid.h): buoyancy from the water's
// level per volume cell, drag towards its velocity, the contacts of rigid_bodies.cpp.
#include "rigid_bodies_grid.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

namespace mr {

namespace {

constexpr float kWaterDensity = 1000.0f;  ///< kg/m^3
/// Metres: shallower samples are dry for the bodies (the grid's own dry depth is 1e-3 by default).
constexpr float kWetDepth = 1e-3f;
/// The surface's slope the pressure gradient takes at most (a shoreline's level jumps).
constexpr float kMostSlope = 1.0f;

size_t index_of(const std::vector<RigidBody>& bodies, uint32_t id) {
    const auto it = std::find_if(bodies.begin(), bodies.end(), [&](const RigidBody& b) { return b.id == id; });
    return size_t(it - bodies.begin());
}

}  // namespace

GridBodies::Cells GridBodies::make_cells(const RigidShape& shape) {
    Cells c;
    const int n = kGridCellsPerAxis;
    const Vec3 ext = glm::max(shape.sample_extent, Vec3(1e-4f));
    c.half = ext / float(n);
    for (int a = 0; a < n; ++a)
        for (int b = 0; b < n; ++b)
            for (int k = 0; k < n; ++k) {
                const Vec3 p = -ext + Vec3(float(2 * a + 1), float(2 * b + 1), float(2 * k + 1)) * c.half;
                if (shape.kind == BodyShape::Box || shape.distance(p) < 0.0f) c.cells.emplace_back(p, 1.0f);
            }
    if (c.cells.empty()) c.cells.emplace_back(Vec3(0.0f), 1.0f);
    const float each = shape.volume / float(c.cells.size());  // the cells hold the shape's volume
    for (glm::vec4& v : c.cells) v.w = each;
    c.length = std::cbrt(std::max(shape.volume, 1e-9f));
    return c;
}

Result<uint32_t> GridBodies::add(const BodyDef& def) {
    auto id = bodies_.add(def);
    if (id) cells_.push_back(make_cells(bodies_.all().back().shape));
    return id;
}

Status GridBodies::remove(uint32_t id) {
    const size_t i = index_of(bodies_.all(), id);
    auto r = bodies_.remove(id);
    if (r) cells_.erase(cells_.begin() + std::ptrdiff_t(i));
    return r;
}

Status GridBodies::set_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                              const Vec3& angular_velocity) {
    return bodies_.set_motion(id, position, orientation, velocity, angular_velocity);
}

bool GridBodies::water_at(const HeightfieldWater& w, const Terrain& terrain, float x, float z, float& level, Vec3& velocity) {
    if (w.rows < 2 || w.columns < 2 || terrain.rows() != w.rows || terrain.columns() != w.columns || w.depth.size() != w.size())
        return false;
    const float fx = (x - w.origin.x) / w.spacing, fz = (z - w.origin.z) / w.spacing;
    if (!(fx >= 0.0f && fz >= 0.0f && fx <= float(w.columns - 1) && fz <= float(w.rows - 1))) return false;  // NaN too
    const int j0 = std::min(int(fx), w.columns - 2), i0 = std::min(int(fz), w.rows - 2);
    const float tx = fx - float(j0), tz = fz - float(i0);
    const bool moving = w.velocity.size() == w.size();
    float sum = 0.0f, lv = 0.0f;
    Vec3 u(0.0f);
    for (int c = 0; c < 4; ++c) {
        const int i = i0 + (c >> 1), j = j0 + (c & 1);
        const float wt = ((c & 1) ? tx : 1.0f - tx) * ((c >> 1) ? tz : 1.0f - tz);
        const size_t k = size_t(i) * size_t(w.columns) + size_t(j);
        if (!(w.depth[k] > kWetDepth) || wt <= 0.0f) continue;
        sum += wt;
        lv += wt * (terrain.sample(i, j) + w.depth[k]);
        if (moving) u += wt * Vec3(w.velocity[k].x, 0.0f, w.velocity[k].z);
    }
    if (sum < 1e-6f) return false;
    level = lv / sum;
    velocity = u / sum;
    return true;
}

float GridBodies::push(RigidBody& b, const Cells& c, const HeightfieldWater& w, const Terrain& terrain, float dt,
                       float gravity) const {
    const glm::mat3 R = glm::mat3_cast(b.q);
    // A cell's vertical half extent in the world (its box turned with the body).
    const float e = std::max(std::abs(R[0].y) * c.half.x + std::abs(R[1].y) * c.half.y + std::abs(R[2].y) * c.half.z, 1e-6f);
    // The surface's slope under the body's centre: the pressure gradient's horizontal part.
    Vec3 slope(0.0f);
    {
        const float h = w.spacing;
        float l[4];
        Vec3 u;
        bool all = true;
        const Vec3 at[4] = {b.x + Vec3(h, 0, 0), b.x - Vec3(h, 0, 0), b.x + Vec3(0, 0, h), b.x - Vec3(0, 0, h)};
        for (int k = 0; k < 4; ++k) all = all && water_at(w, terrain, at[k].x, at[k].z, l[k], u);
        if (all)
            slope = Vec3(std::clamp((l[0] - l[1]) / (2.0f * h), -kMostSlope, kMostSlope), 0.0f,
                         std::clamp((l[2] - l[3]) / (2.0f * h), -kMostSlope, kMostSlope));
    }
    const Vec3 up(-slope.x, 1.0f, -slope.z);
    Vec3 force(0.0f), torque(0.0f), flow(0.0f);
    float drag = 0.0f, submerged = 0.0f;
    for (const glm::vec4& cell : c.cells) {
        const Vec3 r = R * Vec3(cell);
        const Vec3 p = b.x + r;
        float level;
        Vec3 u;
        if (!water_at(w, terrain, p.x, p.z, level, u)) continue;
        const float share = std::clamp((level - p.y + e) / (2.0f * e), 0.0f, 1.0f);
        if (share <= 0.0f) continue;
        const float vs = share * cell.w;
        submerged += vs;
        const Vec3 f = kWaterDensity * gravity * vs * up;
        force += f;
        torque += glm::cross(r, f);
        const Vec3 rel = b.v + glm::cross(b.w, r) - u;
        const float k = kWaterDensity * vs * (kGridDragLinear + kGridDragQuadratic / c.length * glm::length(rel));
        drag += k;
        flow += k * u;
    }
    if (submerged <= 0.0f) return 0.0f;
    // The drag, implicit: the velocity this substep ends with (gravity's, which predict()
    // adds next, included) relaxes towards the submerged cells' water velocity.
    const Vec3 fall(0.0f, gravity * dt, 0.0f);
    const float keep = std::exp(-drag * b.inv_mass * dt);
    const Vec3 target = flow / drag;
    b.v = target + (b.v + force * (b.inv_mass * dt) - fall - target) * keep + fall;
    b.w = (b.w + b.inv_inertia_world() * torque * dt) * keep;
    return std::clamp(submerged / b.shape.volume, 0.0f, 1.0f);
}

void GridBodies::step(const HeightfieldWater& w, const Terrain& terrain, float frame_dt, float gravity) {
    if (bodies_.empty()) return;
    if (frame_dt > 0.0f) {
        const float dt = frame_dt / float(kGridBodySubsteps);
        std::vector<RigidBody>& all = bodies_.all();
        std::vector<float> share(all.size(), 0.0f);
        std::vector<RigidBody> predicted(all.size());
        for (int s = 0; s < kGridBodySubsteps; ++s) {
            for (size_t i = 0; i < all.size(); ++i) share[i] = push(all[i], cells_[i], w, terrain, dt, gravity);
            bodies_.predict(dt, gravity);
            for (size_t i = 0; i < all.size(); ++i) {
                predicted[i].x = all[i].x, predicted[i].q = all[i].q;
                predicted[i].v = all[i].v, predicted[i].w = all[i].w;
            }
            bodies_.contacts(terrain, dt);
            bodies_.velocities(dt, gravity);
            // A body no contact moved keeps its velocity as predicted: the poses' change
            // over a substep rounds it (a drift of 1e-4 m/s per substep at 10 m from the
            // origin is below a float's step of the position and would never add up).
            for (size_t i = 0; i < all.size(); ++i)
                if (all[i].x == predicted[i].x && all[i].q == predicted[i].q) all[i].v = predicted[i].v, all[i].w = predicted[i].w;
        }
        for (size_t i = 0; i < all.size(); ++i) all[i].submerged = share[i];
    }
    bodies_.update_states();
}

}  // namespace mr
