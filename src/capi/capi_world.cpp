// The C API's frame and its reads (include/metariver/metariver.h): step, stats, the
// particles and the surface as borrowed views or copies, the terrain, the scene as TOML
// and live edits of it, the water grid and its volumes.
#include "capi_internal.h"

#include <metariver/scene_keys.h>

#include <cmath>
#include <cstring>
#include <filesystem>

using mr::capi::fail;
using mr::capi::guarded;
using mr::capi::heightfield_of;
using mr::capi::null_argument;

// The views hand out the Simulation's own arrays: glm::vec3 must be three packed floats.
static_assert(sizeof(mr::Vec3) == 3 * sizeof(float), "Vec3 must be 3 packed floats for the C views");

namespace {

const float* floats(const std::vector<mr::Vec3>& v) { return v.empty() ? nullptr : &v[0].x; }

/// Copies the active particles' `field` (position or velocity) into `out`, in index order.
void copy_active(const mr::Particles& p, const std::vector<mr::Vec3>& field, float* out) {
    size_t k = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        if (!p.active[i]) continue;
        std::memcpy(out + 3 * k, &field[i].x, 3 * sizeof(float));
        ++k;
    }
}

/// Writes `text` and its NUL into the caller's buffer of `capacity` bytes; *length: the
/// text's length (MR_ERROR_BUFFER_TOO_SMALL, nothing written, when it does not fit).
mr_status copy_text(const mr_world* world, const char* function, const std::string& text, char* buffer, size_t capacity,
                    size_t* length) {
    *length = text.size();
    if (capacity < text.size() + 1)
        return fail(world, MR_ERROR_BUFFER_TOO_SMALL,
                    fmt::format("{}: capacity: {} bytes is smaller than the {} the text needs (its length and the NUL)",
                                function, capacity, text.size() + 1));
    std::memcpy(buffer, text.c_str(), text.size() + 1);
    return MR_OK;
}

}  // namespace

extern "C" {

mr_status mr_world_step(mr_world* world, float frame_dt) {
    return guarded(world, "mr_world_step", true, [&] {
        if (!(std::isfinite(frame_dt) && frame_dt > 0.0f && frame_dt <= 1.0f))
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_step: frame_dt: must be in (0, 1] seconds (got {})", frame_dt));
        world->sim->step(frame_dt);
        world->time_s += frame_dt;
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_stats(const mr_world* world, mr_stats* out) {
    return guarded(world, "mr_world_stats", false, [&] {
        if (!out) return null_argument(world, "mr_world_stats", "out");
        const mr::Simulation& sim = *world->sim;
        const mr::FrameTimings& t = sim.last_timings();
        mr_stats s{};
        s.frame = sim.frame();
        s.time_s = world->time_s;
        s.particle_slots = sim.particles().size();
        s.active_particles = sim.particles().active_count();
        s.tunneled = sim.counters().tunneled;
        s.surface_vertices = sim.surface().vertex_count();
        s.surface_triangles = sim.surface().triangle_count();
        s.simulate_ms = t.simulate_ms;
        s.field_ms = t.field_ms;
        s.surface_ms = t.surface_ms;
        *out = s;
        return MR_OK;
    });
}

mr_status mr_world_particles(const mr_world* world, mr_particles_view* out) {
    return guarded(world, "mr_world_particles", false, [&] {
        if (!out) return null_argument(world, "mr_world_particles", "out");
        const mr::Particles& p = world->sim->particles();
        out->positions = floats(p.position);
        out->velocities = floats(p.velocity);
        out->active = p.active.empty() ? nullptr : p.active.data();
        out->count = p.size();
        return MR_OK;
    });
}

mr_status mr_world_copy_particles(const mr_world* world, float* positions, float* velocities, size_t capacity,
                                  size_t* count) {
    return guarded(world, "mr_world_copy_particles", false, [&] {
        if (!count) return null_argument(world, "mr_world_copy_particles", "count");
        const mr::Particles& p = world->sim->particles();
        const size_t active = p.active_count();
        *count = active;
        if (!positions && !velocities) return MR_OK;
        if (capacity < active)
            return fail(world, MR_ERROR_BUFFER_TOO_SMALL,
                        fmt::format("mr_world_copy_particles: capacity: {} is smaller than the {} active particles",
                                    capacity, active));
        if (positions) copy_active(p, p.position, positions);
        if (velocities) copy_active(p, p.velocity, velocities);
        return MR_OK;
    });
}

mr_status mr_world_surface(const mr_world* world, mr_surface_view* out) {
    return guarded(world, "mr_world_surface", false, [&] {
        if (!out) return null_argument(world, "mr_world_surface", "out");
        const mr::SurfaceMesh& m = world->sim->surface();
        out->positions = floats(m.positions);
        out->normals = floats(m.normals);
        out->vertex_count = m.vertex_count();
        out->indices = m.indices.empty() ? nullptr : m.indices.data();
        out->index_count = m.indices.size();
        return MR_OK;
    });
}

mr_status mr_world_copy_surface(const mr_world* world, float* positions, float* normals, size_t vertex_capacity,
                                uint32_t* indices, size_t index_capacity, size_t* vertex_count, size_t* index_count) {
    return guarded(world, "mr_world_copy_surface", false, [&] {
        if (!vertex_count) return null_argument(world, "mr_world_copy_surface", "vertex_count");
        if (!index_count) return null_argument(world, "mr_world_copy_surface", "index_count");
        const mr::SurfaceMesh& m = world->sim->surface();
        *vertex_count = m.vertex_count();
        *index_count = m.indices.size();
        if ((positions || normals) && vertex_capacity < m.vertex_count())
            return fail(world, MR_ERROR_BUFFER_TOO_SMALL,
                        fmt::format("mr_world_copy_surface: vertex_capacity: {} is smaller than the {} vertices",
                                    vertex_capacity, m.vertex_count()));
        if (indices && index_capacity < m.indices.size())
            return fail(world, MR_ERROR_BUFFER_TOO_SMALL,
                        fmt::format("mr_world_copy_surface: index_capacity: {} is smaller than the {} indices",
                                    index_capacity, m.indices.size()));
        const size_t bytes = m.vertex_count() * 3 * sizeof(float);
        if (positions && bytes) std::memcpy(positions, floats(m.positions), bytes);
        if (normals && bytes) std::memcpy(normals, floats(m.normals), bytes);
        if (indices && !m.indices.empty()) std::memcpy(indices, m.indices.data(), m.indices.size() * sizeof(uint32_t));
        return MR_OK;
    });
}

mr_status mr_world_terrain(const mr_world* world, mr_terrain_info* out) {
    return guarded(world, "mr_world_terrain", false, [&] {
        if (!out) return null_argument(world, "mr_world_terrain", "out");
        const mr::Terrain& t = world->sim->terrain();
        out->columns = t.columns();
        out->rows = t.rows();
        out->area_scale = t.area_scale();
        out->min_y = t.mesh_bounds().min.y;
        out->max_y = t.mesh_bounds().max.y;
        return MR_OK;
    });
}

mr_status mr_world_copy_terrain_heights(const mr_world* world, float* heights, size_t capacity) {
    return guarded(world, "mr_world_copy_terrain_heights", false, [&] {
        if (!heights) return null_argument(world, "mr_world_copy_terrain_heights", "heights");
        const mr::Terrain& t = world->sim->terrain();
        const size_t n = static_cast<size_t>(t.rows()) * static_cast<size_t>(t.columns());
        if (capacity < n)
            return fail(world, MR_ERROR_BUFFER_TOO_SMALL,
                        fmt::format("mr_world_copy_terrain_heights: capacity: {} is smaller than the {} samples "
                                    "({} rows x {} columns)", capacity, n, t.rows(), t.columns()));
        const auto vertices = t.vertices();  // vertex i * columns + j: row i (z), column j (x)
        for (size_t i = 0; i < n; ++i) heights[i] = vertices[i].y;
        return MR_OK;
    });
}

mr_status mr_world_heightfield(const mr_world* world, mr_heightfield_info* out) {
    return guarded(world, "mr_world_heightfield", false, [&] {
        if (!out) return null_argument(world, "mr_world_heightfield", "out");
        mr_status status = MR_OK;
        const mr::HeightfieldWater* w = heightfield_of(world, "mr_world_heightfield", status);
        if (!w) return status;
        *out = mr_heightfield_info{w->columns, w->rows, w->spacing, {w->origin.x, w->origin.z}};
        return MR_OK;
    });
}

mr_status mr_world_copy_heightfield(const mr_world* world, float* depth, float* velocity, float* bed, size_t capacity) {
    return guarded(world, "mr_world_copy_heightfield", false, [&] {
        mr_status status = MR_OK;
        const mr::HeightfieldWater* w = heightfield_of(world, "mr_world_copy_heightfield", status);
        if (!w) return status;
        const size_t n = w->size();
        if ((depth || velocity || bed) && capacity < n)
            return fail(world, MR_ERROR_BUFFER_TOO_SMALL,
                        fmt::format("mr_world_copy_heightfield: capacity: {} is smaller than the {} cells ({} rows x {} "
                                    "columns)", capacity, n, w->rows, w->columns));
        const auto ground = world->sim->terrain().vertices();
        for (size_t k = 0; k < n; ++k) {
            if (depth) depth[k] = w->depth[k];
            if (velocity) {
                const mr::Vec3 v = k < w->velocity.size() ? w->velocity[k] : mr::Vec3(0.0f);
                velocity[2 * k] = v.x;
                velocity[2 * k + 1] = v.z;
            }
            if (bed) bed[k] = k < ground.size() ? ground[k].y : 0.0f;
        }
        return MR_OK;
    });
}

mr_status mr_world_water_balance(const mr_world* world, mr_water_balance* out) {
    return guarded(world, "mr_world_water_balance", false, [&] {
        if (!out) return null_argument(world, "mr_world_water_balance", "out");
        mr_status status = MR_OK;
        if (!heightfield_of(world, "mr_world_water_balance", status)) return status;
        const mr::SweSolver* grid = world->sim->grid();
        if (!grid)
            return fail(world, MR_ERROR_UNSUPPORTED,
                        fmt::format("mr_world_water_balance: solver = \"{}\" keeps no water balance",
                                    world->sim->solver_entry().kind.name));
        const mr::SweBalance b = grid->balance();
        *out = mr_water_balance{.initial = b.initial, .inflow = b.inflow, .rain = b.rain, .outflow = b.outflow,
                                .sunk = b.sunk, .exchanged = b.exchanged, .stored = b.stored, .error = b.error(),
                                .simulated_s = grid->simulated_s(), .substeps = grid->counters().substeps,
                                .rain_set = grid->rain_set() ? 1 : 0};
        return MR_OK;
    });
}

mr_status mr_world_scene_toml(const mr_world* world, char* buffer, size_t capacity, size_t* length) {
    return guarded(world, "mr_world_scene_toml", false, [&] {
        if (!length) return null_argument(world, "mr_world_scene_toml", "length");
        if (!buffer && capacity > 0) return null_argument(world, "mr_world_scene_toml", "buffer");
        mr::SceneDef def = world->sim->requested();
        // The text may be saved anywhere: a relative heightmap path would be read relative to it.
        if (!def.source.heightmap.empty())
            def.source.heightmap = std::filesystem::absolute(def.source.heightmap).lexically_normal().string();
        return copy_text(world, "mr_world_scene_toml", mr::scene_to_toml(def, world->base), buffer, capacity, length);
    });
}

mr_status mr_world_warnings(const mr_world* world, char* buffer, size_t capacity, size_t* length) {
    return guarded(world, "mr_world_warnings", false, [&] {
        if (!length) return null_argument(world, "mr_world_warnings", "length");
        if (!buffer && capacity > 0) return null_argument(world, "mr_world_warnings", "buffer");
        std::string text;
        for (const std::string& w : world->sim->warnings()) text += (text.empty() ? "" : "\n") + w;
        return copy_text(world, "mr_world_warnings", text, buffer, capacity, length);
    });
}

mr_status mr_world_apply_toml(mr_world* world, const char* toml, int32_t* applied) {
    return guarded(world, "mr_world_apply_toml", true, [&] {
        if (!toml) return null_argument(world, "mr_world_apply_toml", "toml");
        auto next = mr::parse_scene_toml(toml, "toml", world->sim->requested());
        if (!next) return fail(world, MR_ERROR_SCENE, "mr_world_apply_toml: " + next.error().message);
        auto r = world->sim->apply(next.value());
        if (!r) return fail(world, MR_ERROR_SCENE, "mr_world_apply_toml: " + r.error().message);
        if (applied) *applied = r->applied ? 1 : 0;
        if (!r->applied) {
            world->error = fmt::format("mr_world_apply_toml: {}: needs a new world (create one from the edited "
                                       "scene); nothing was changed", r->rebuild_key);
            return MR_OK;
        }
        world->query_fresh = false;
        return MR_OK;
    });
}

}  // extern "C"
