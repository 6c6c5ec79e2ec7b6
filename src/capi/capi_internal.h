// The C API's world (include/metariver/metariver.h) and the boundary every entry point
// goes through: NULL checks, the world's own thread arena, exceptions turned into
// MR_ERROR_INTERNAL, and the message of the latest failed call.
#pragma once

#include <metariver/metariver.h>
#include <metariver/scene.h>
#include <metariver/water_query.h>

#include <tbb/task_arena.h>

#include <fmt/format.h>

#include <exception>
#include <memory>
#include <new>
#include <string>
#include <utility>

/// The opaque handle: one Simulation, the threads its work runs on, the queries of its
/// latest frame and the message of the latest failed call (mutable: the header's const
/// reads, stats and views, record their refusals too).
struct mr_world {
    /// At most mr_world_desc.threads threads; every call that does work runs inside it:
    /// Simulation::create and the water queries use it, the Simulation's own work (step,
    /// edits) its arena of the same count (Simulation::set_threads, set at creation).
    mutable tbb::task_arena arena;
    std::unique_ptr<mr::Simulation> sim;
    /// The preset the scene TOML starts from (`preset = "<base>"`): the world's preset
    /// or "default".
    std::string base = "default";
    double time_s = 0.0;  ///< simulated seconds (sum of the steps' frame_dt)
    mutable std::string error;
    /// The water queries of the latest frame: updated on the first query after a step or
    /// an edit (query_fresh false).
    mr::WaterQuery query;
    bool query_fresh = false;

    explicit mr_world(int threads) : arena(threads > 0 ? threads : tbb::task_arena::automatic) {}
};

namespace mr::capi {

/// Records `message` as the world's latest error (when there is a world) and returns `code`.
inline mr_status fail(const mr_world* w, mr_status code, std::string message) {
    if (w) w->error = std::move(message);
    return code;
}

/// "<function>: <name> is NULL" as MR_ERROR_NULL_ARGUMENT.
inline mr_status null_argument(const mr_world* w, const char* function, const char* name) {
    return fail(w, MR_ERROR_NULL_ARGUMENT, fmt::format("{}: {} is NULL", function, name));
}

/// Runs `fn` (returning mr_status) for the world `w` of function `function`: a NULL
/// world is MR_ERROR_NULL_ARGUMENT; a C++ exception becomes MR_ERROR_INTERNAL with its
/// what(). `in_arena`: inside the world's thread arena (calls that do work).
template <class F>
mr_status guarded(const mr_world* w, const char* function, bool in_arena, F&& fn) {
    if (!w) return MR_ERROR_NULL_ARGUMENT;
    try {
        if (in_arena) return w->arena.execute([&] { return fn(); });
        return fn();
    } catch (const std::bad_alloc&) {
        return fail(w, MR_ERROR_INTERNAL, fmt::format("{}: out of memory", function));
    } catch (const std::exception& e) {
        return fail(w, MR_ERROR_INTERNAL, fmt::format("{}: internal error: {}", function, e.what()));
    } catch (...) {
        return fail(w, MR_ERROR_INTERNAL, fmt::format("{}: internal error (unknown exception)", function));
    }
}

/// Whether all three of p[0..2] are finite.
bool finite3(const float* p);
/// "x, y, z" of a 3-float array for messages.
std::string show3(const float* p);
/// The world's heightfield water, or null and `status` an MR_ERROR_UNSUPPORTED naming
/// `function` and the solver (whose water is particles).
const mr::HeightfieldWater* heightfield_of(const mr_world* world, const char* function, mr_status& status);

}  // namespace mr::capi
