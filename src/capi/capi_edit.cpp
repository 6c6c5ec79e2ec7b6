// The C API's interaction (include/metariver/metariver.h): sculpt, pour, push, move the
// source, replace the box sinks, rain per cell on the grid. Each checks its arguments first (nothing changes on a
// refusal) and marks the water queries stale.
#include "capi_internal.h"

#include <metariver/emitters.h>
#include <metariver/particles.h>
#include <metariver/scene_keys.h>

#include <cmath>
#include <cstring>
#include <stdexcept>
#include <string_view>
#include <type_traits>

using mr::capi::fail;
using mr::capi::finite3;
using mr::capi::guarded;
using mr::capi::null_argument;
using mr::capi::show3;

namespace {

mr::Vec3 vec3(const float* p) { return {p[0], p[1], p[2]}; }

/// MR_ERROR_UNSUPPORTED when the world's solver refuses the edit (`why`: its entry's reason).
mr_status unsupported(const mr_world* w, const char* function, std::string_view why) {
    return fail(w, MR_ERROR_UNSUPPORTED,
                fmt::format("{}: solver = \"{}\" {}", function, w->sim->solver_entry().kind.name, why));
}

/// The scene's list of more box sinks ([[sink.box]]).
const mr::SceneList& sink_box_list() {
    for (const mr::SceneList& l : mr::scene_lists())
        if (l.name == "sink.box") return l;
    throw std::logic_error("the scene has no sink.box list");
}

}  // namespace

extern "C" {

mr_status mr_world_sculpt(mr_world* world, const mr_brush* brush) {
    return guarded(world, "mr_world_sculpt", true, [&] {
        if (!brush) return null_argument(world, "mr_world_sculpt", "brush");
        // A C caller may store any int in the enum; C++ may not read one outside 0..3 as
        // mr_brush_mode, so the mode is read as its underlying integer.
        std::underlying_type_t<mr_brush_mode> mode = 0;
        static_assert(sizeof mode == sizeof brush->mode);
        std::memcpy(&mode, &brush->mode, sizeof mode);
        if (mode < MR_BRUSH_RAISE || mode > MR_BRUSH_FLATTEN)
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_sculpt: brush.mode: must be MR_BRUSH_RAISE (0) .. MR_BRUSH_FLATTEN (3) "
                                    "(got {})", static_cast<long long>(mode)));
        const std::string_view why = world->sim->solver_entry().no_sculpt;
        if (!why.empty()) return unsupported(world, "mr_world_sculpt", why);
        const mr::Brush b{.x = brush->x, .z = brush->z, .radius = brush->radius, .strength = brush->strength,
                          .mode = static_cast<mr::BrushMode>(mode), .target = brush->target};
        auto edit = world->sim->sculpt(b);
        if (!edit) return fail(world, MR_ERROR_INVALID_ARGUMENT, "mr_world_sculpt: " + edit.error().message);
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_pour(mr_world* world, const float center[3], int32_t count) {
    return guarded(world, "mr_world_pour", true, [&] {
        if (!center) return null_argument(world, "mr_world_pour", "center");
        if (!finite3(center))
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_pour: center: must be finite (got {})", show3(center)));
        if (count < 1 || count > mr::kMaxParticles)
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_pour: count: must be in [1, {}] (got {})", mr::kMaxParticles, count));
        world->sim->pour(vec3(center), count);
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_push(mr_world* world, const float center[3], float radius, const float velocity[3],
                        size_t* pushed) {
    return guarded(world, "mr_world_push", true, [&] {
        if (!center) return null_argument(world, "mr_world_push", "center");
        if (!velocity) return null_argument(world, "mr_world_push", "velocity");
        if (!finite3(center) || !finite3(velocity))
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_push: {}: must be finite (got {})", finite3(center) ? "velocity" : "center",
                                    show3(finite3(center) ? velocity : center)));
        if (!(std::isfinite(radius) && radius > 0.0f))
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_push: radius: must be finite and > 0 metres (got {})", radius));
        const std::string_view why = world->sim->solver_entry().no_push;
        if (!why.empty()) return unsupported(world, "mr_world_push", why);
        auto n = world->sim->push(vec3(center), radius, vec3(velocity));
        if (!n) return fail(world, MR_ERROR_INVALID_ARGUMENT, "mr_world_push: " + n.error().message);
        if (pushed) *pushed = n.value();
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_move_source(mr_world* world, const float center[3]) {
    return guarded(world, "mr_world_move_source", true, [&] {
        if (!center) return null_argument(world, "mr_world_move_source", "center");
        if (!finite3(center))
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_move_source: center: must be finite (got {})", show3(center)));
        if (auto s = world->sim->move_source(vec3(center)); !s)
            return fail(world, MR_ERROR_INVALID_ARGUMENT, "mr_world_move_source: center: " + s.error().message);
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_set_sink_boxes(mr_world* world, const float* boxes, size_t count) {
    return guarded(world, "mr_world_set_sink_boxes", true, [&] {
        if (!boxes && count > 0) return null_argument(world, "mr_world_set_sink_boxes", "boxes");
        if (count > mr::kMaxMoreSinks)
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_set_sink_boxes: count: must be in [0, {}] (got {})", mr::kMaxMoreSinks,
                                    count));
        mr::SceneDef next = world->sim->requested();
        if (next.sink.kind == mr::SinkKind::Box) next.sink.kind = mr::SinkKind::None;  // its box is replaced too
        next.sink.boxes.clear();
        for (size_t i = 0; i < count; ++i) {
            const float* b = boxes + 6 * i;
            if (!finite3(b) || !finite3(b + 3) || b[0] > b[3] || b[1] > b[4] || b[2] > b[5])
                return fail(world, MR_ERROR_INVALID_ARGUMENT,
                            fmt::format("mr_world_set_sink_boxes: boxes[{}]: min ({}) and max ({}) must be finite "
                                        "with min <= max", i, show3(b), show3(b + 3)));
            next.sink.boxes.push_back({vec3(b), vec3(b + 3)});
        }
        if (count > 0 && world->sim->grid())  // (the key table counts the grid's solvers as readers)
            return unsupported(world, "mr_world_set_sink_boxes",
                               "has no sink boxes: its sinks are [[swe.sinks]] (mr_world_apply_toml)");
        // apply() would take boxes a solver that does not read them ignores.
        if (count > 0 && !sink_box_list().readers(next))
            return unsupported(world, "mr_world_set_sink_boxes",
                               fmt::format("reads no sink.box (read by {})", sink_box_list().readers.text));
        auto r = world->sim->apply(next);
        if (!r) return fail(world, MR_ERROR_SCENE, "mr_world_set_sink_boxes: " + r.error().message);
        if (!r->applied)
            return fail(world, MR_ERROR_UNSUPPORTED,
                        fmt::format("mr_world_set_sink_boxes: {}: needs a new world; nothing was changed",
                                    r->rebuild_key));
        world->query_fresh = false;
        return MR_OK;
    });
}

mr_status mr_world_set_rain(mr_world* world, const float* mm_per_h, size_t count) {
    return guarded(world, "mr_world_set_rain", false, [&] {
        if (!mm_per_h && count > 0) return null_argument(world, "mr_world_set_rain", "mm_per_h");
        mr_status status = MR_OK;
        const mr::HeightfieldWater* grid = mr::capi::heightfield_of(world, "mr_world_set_rain", status);
        if (!grid) return status;
        if (count != 0 && count != grid->size())
            return fail(world, MR_ERROR_INVALID_ARGUMENT,
                        fmt::format("mr_world_set_rain: count: must be the grid's {} cells ({} rows x {} columns), or 0 "
                                    "with mm_per_h NULL for the scene's rain (got {})", grid->size(), grid->rows,
                                    grid->columns, count));
        if (auto s = world->sim->set_rain({mm_per_h, mm_per_h ? count : 0}); !s)
            return fail(world, world->sim->grid() ? MR_ERROR_INVALID_ARGUMENT : MR_ERROR_UNSUPPORTED,
                        "mr_world_set_rain: " + s.error().message);
        return MR_OK;
    });
}

}  // extern "C"
