// The C API's bodies (include/metariver/metariver.h; bodies.h): add, remove, move and read
// the rigid bodies of a PBF, swe or hybrid world. Each checks its arguments first (nothing changes on a
// refusal) and marks the water queries stale when the water's neighbours changed.
#include "capi_internal.h"

#include <metariver/bodies.h>
#include <metariver/scene_keys.h>

#include <cstring>
#include <filesystem>

using mr::capi::fail;
using mr::capi::guarded;
using mr::capi::null_argument;

namespace {

mr::Vec3 vec3(const float* p) { return {p[0], p[1], p[2]}; }
void put3(const mr::Vec3& v, float* out) { std::memcpy(out, &v.x, 3 * sizeof(float)); }

/// MR_ERROR_UNSUPPORTED when the world's solver has no bodies (all but PBF, swe and hybrid).
bool no_bodies(const mr_world* w, const char* function, mr_status& status) {
    for (const mr::SceneList& l : mr::scene_lists())  // the key table says which solvers move bodies
        if (l.name == "bodies" && l.readers(w->sim->def())) return false;
    status = fail(w, MR_ERROR_UNSUPPORTED,
                  fmt::format("{}: solver = \"{}\" has no bodies (use solver = \"pbf\", \"swe\" or \"hybrid\")", function,
                              w->sim->solver_entry().kind.name));
    return true;
}

}  // namespace

extern "C" {

mr_body_desc mr_body_desc_default(void) {
    const mr::BodyDef d;
    mr_body_desc out{};
    out.shape = static_cast<int32_t>(d.shape);
    put3(d.size, out.size);
    out.mesh = nullptr;
    out.density = d.density;
    put3(d.position, out.position);
    put3(d.rotation, out.rotation);
    put3(d.velocity, out.velocity);
    put3(d.angular_velocity, out.angular_velocity);
    out.friction = d.friction;
    return out;
}

mr_status mr_world_add_body(mr_world* world, const mr_body_desc* desc, uint32_t* out_id) {
    return guarded(world, "mr_world_add_body", true, [&] {
        if (!desc) return null_argument(world, "mr_world_add_body", "desc");
        if (!out_id) return null_argument(world, "mr_world_add_body", "out_id");
        if (mr_status s = MR_OK; no_bodies(world, "mr_world_add_body", s)) return s;
        if (desc->shape < MR_BODY_BOX || desc->shape > MR_BODY_TRIANGLE_MESH)
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_add_body: shape: must be MR_BODY_BOX (0) .. MR_BODY_TRIANGLE_MESH (4) "
                                    "(got {})", desc->shape));
        mr::BodyDef d{.shape = static_cast<mr::BodyShape>(desc->shape),
                      .size = vec3(desc->size),
                      .mesh = desc->mesh ? desc->mesh : "",
                      .density = desc->density,
                      .position = vec3(desc->position),
                      .rotation = vec3(desc->rotation),
                      .velocity = vec3(desc->velocity),
                      .angular_velocity = vec3(desc->angular_velocity),
                      .friction = desc->friction};
        if (auto v = mr::validate_body(d); !v)
            return fail(world, MR_ERROR_INVALID_ARGUMENT, "mr_world_add_body: " + v.error().message);
        std::error_code ec;
        if (!d.mesh.empty() && !std::filesystem::is_regular_file(d.mesh, ec))
            return fail(world, MR_ERROR_IO, fmt::format("mr_world_add_body: mesh: {}: no such file", d.mesh));
        auto id = world->sim->add_body(d);
        if (!id) {
            const bool file = !d.mesh.empty() && id.error().message.find(d.mesh) != std::string::npos;
            return fail(world, file ? MR_ERROR_IO : MR_ERROR_INVALID_ARGUMENT, "mr_world_add_body: " + id.error().message);
        }
        *out_id = id.value();
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_remove_body(mr_world* world, uint32_t id) {
    return guarded(world, "mr_world_remove_body", true, [&] {
        if (auto s = world->sim->remove_body(id); !s)
            return fail(world, MR_ERROR_INVALID_ARGUMENT, "mr_world_remove_body: " + s.error().message);
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_set_body_motion(mr_world* world, uint32_t id, const float position[3], const float orientation[4],
                                   const float velocity[3], const float angular_velocity[3]) {
    return guarded(world, "mr_world_set_body_motion", true, [&] {
        const char* f = "mr_world_set_body_motion";
        if (!position) return null_argument(world, f, "position");
        if (!orientation) return null_argument(world, f, "orientation");
        if (!velocity) return null_argument(world, f, "velocity");
        if (!angular_velocity) return null_argument(world, f, "angular_velocity");
        const glm::quat q(orientation[3], orientation[0], orientation[1], orientation[2]);  // w, x, y, z
        if (auto s = world->sim->set_body_motion(id, vec3(position), q, vec3(velocity), vec3(angular_velocity)); !s)
            return fail(world, MR_ERROR_INVALID_ARGUMENT, fmt::format("{}: {}", f, s.error().message));
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_bodies(const mr_world* world, mr_body_state* out, size_t capacity, size_t* count) {
    return guarded(world, "mr_world_bodies", false, [&] {
        if (!count) return null_argument(world, "mr_world_bodies", "count");
        const std::span<const mr::BodyState> bodies = world->sim->bodies();
        *count = bodies.size();
        if (!out) return MR_OK;
        if (capacity < bodies.size())
            return fail(world, MR_ERROR_BUFFER_TOO_SMALL,
                        fmt::format("mr_world_bodies: capacity: {} is smaller than the {} bodies", capacity,
                                    bodies.size()));
        for (size_t i = 0; i < bodies.size(); ++i) {
            const mr::BodyState& b = bodies[i];
            mr_body_state& o = out[i];
            o.id = b.id;
            o.shape = static_cast<int32_t>(b.shape);
            put3(b.size, o.size);
            put3(b.position, o.position);
            const float q[4] = {b.orientation.x, b.orientation.y, b.orientation.z, b.orientation.w};
            std::memcpy(o.orientation, q, sizeof q);
            put3(b.velocity, o.velocity);
            put3(b.angular_velocity, o.angular_velocity);
            o.mass = b.mass;
            o.submerged_fraction = b.submerged_fraction;
        }
        return MR_OK;
    });
}

}  // extern "C"
