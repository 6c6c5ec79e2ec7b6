// The solver registry (include/metariver/solver_registry.h) and the three built-in
// solvers: the only place that names the concrete solver types (their constructors and
// the live edits' set_params). A build without Bullet (METARIVER_WITH_BULLET=OFF, which
// defines METARIVER_NO_BULLET here) has springs and pbf only.
#include <metariver/solver_registry.h>

#ifndef METARIVER_NO_BULLET
#include <metariver/bullet_solver.h>
#endif
#include <metariver/hybrid_solver.h>
#include <metariver/particles.h>
#include <metariver/pbf_solver.h>
#include <metariver/scene.h>
#include <metariver/spring_solver.h>
#include <metariver/swe_solver.h>

#include <fmt/format.h>

#include <algorithm>

namespace mr {

namespace {

/// A live-edit rule for solver type S: `edit` on the solver `create` made (a solver of
/// another type, which a Simulation never passes, asks for a rebuild).
template <class S>
std::function<bool(Solver&, const SceneDef&)> edits(bool (*edit)(S&, const SceneDef&)) {
    return [edit](Solver& solver, const SceneDef& d) {
        auto* s = dynamic_cast<S*>(&solver);
        return s && edit(*s, d);
    };
}

SolverEntry springs_entry() {
    return {
        .kind = SolverKind::Springs,
        .help = "the paper's own physics: gravity, Hooke springs between particles, terrain collision",
        .create = [](const SceneDef& d, const Terrain& t, const Bvh& b) -> std::unique_ptr<Solver> {
            return std::make_unique<SpringSolver>(t, b, d.spawn, d.springs, d.collision, d.integrator, d.seed, d.sink);
        },
        .apply = edits<SpringSolver>([](SpringSolver& s, const SceneDef& d) {
            return s.set_params(d.spawn, d.springs, d.collision, d.integrator, d.sink);
        }),
        .spray_scale = [](const SceneDef& d) {
            const float spacing = d.springs.min_distance > 0.0f ? d.springs.min_distance : 1.0f;
            return SprayScale{.spacing = spacing, .kernel_radius = 2.0f * spacing};
        },
    };
}

#ifndef METARIVER_NO_BULLET
SolverEntry bullet_entry() {
    return {
        .kind = SolverKind::Bullet,
        .help = "the paper's engine physics (2.4) on Bullet: rigid spheres against the terrain",
        .create = [](const SceneDef& d, const Terrain& t, const Bvh&) -> std::unique_ptr<Solver> {
            return std::make_unique<BulletSolver>(t, d.spawn, d.springs, d.integrator, d.bullet, d.seed);
        },
        // Its world is built once from its defs: every key it reads asks for a rebuild.
        .apply = nullptr,
        .spray_scale = [](const SceneDef& d) {
            const float spacing = 2.0f * d.bullet.sphere_radius;
            return SprayScale{.spacing = spacing, .kernel_radius = 2.0f * spacing};
        },
        .no_push = "moves its own bodies; push with pbf or springs",
        .no_sculpt = "holds its own copy of the terrain; sculpt with pbf or springs",
    };
}
#endif

/// Why `kind` is missing from this build, after the registered names ("": it is not left out).
std::string_view left_out(SolverKind kind) {
#ifdef METARIVER_NO_BULLET
    if (kind == SolverKind::Bullet) return "; this build leaves out the Bullet solver (METARIVER_WITH_BULLET=OFF)";
#endif
    (void)kind;
    return "";
}

SolverEntry pbf_entry() {
    return {
        .kind = SolverKind::Pbf,
        .help = "Position Based Fluids (Macklin and Mueller 2013) with the robust terrain collision",
        .create = [](const SceneDef& d, const Terrain& t, const Bvh& b) -> std::unique_ptr<Solver> {
            return std::make_unique<PbfSolver>(t, b, d.spawn, d.pbf, d.collision, d.integrator, d.seed, d.sink);
        },
        .apply = edits<PbfSolver>([](PbfSolver& s, const SceneDef& d) {
            return s.set_params(d.spawn, d.pbf, d.collision, d.integrator, d.sink);
        }),
        .spray_scale = [](const SceneDef& d) { return SprayScale{.spacing = d.pbf.spacing, .kernel_radius = d.pbf.kernel_radius}; },
        .foam_kernel_radius = [](const SceneDef& d) { return d.pbf.kernel_radius; },
        .prefills = true,
        .respawn_to_pool = true,
    };
}

SolverEntry swe_entry() {
    return {
        .kind = SolverKind::Swe,
        .help = "shallow water on the terrain's grid (Audusse et al. 2004, HLL; docs/shallow-water.md): depth and velocity per sample",
        .create = [](const SceneDef& d, const Terrain& t, const Bvh&) -> std::unique_ptr<Solver> {
            return std::make_unique<SweSolver>(t, d.swe, d.spawn.center, d.integrator.gravity);
        },
        .apply = edits<SweSolver>([](SweSolver& s, const SceneDef& d) { return s.set_params(d.swe, d.spawn.center); }),
    };
}

SolverEntry hybrid_entry() {
    return {
        .kind = SolverKind::Hybrid,
        .help = "shallow water on the terrain's grid that becomes PBF particles where it falls over a drop, and back "
                "(docs/waterfalls.md)",
        .create = [](const SceneDef& d, const Terrain& t, const Bvh& b) -> std::unique_ptr<Solver> {
            return std::make_unique<HybridSolver>(t, b, d.hybrid, d.swe, d.spawn.center, d.pbf, d.collision, d.integrator);
        },
        .apply = edits<HybridSolver>([](HybridSolver& s, const SceneDef& d) { return s.set_params(d.hybrid, d.swe, d.spawn.center); }),
        .spray_scale = [](const SceneDef& d) { return SprayScale{.spacing = d.pbf.spacing, .kernel_radius = d.pbf.kernel_radius}; },
        .foam_kernel_radius = [](const SceneDef& d) { return d.pbf.kernel_radius; },  // and the grid's foam (Simulation)
        .no_push = "hands its particles to the grid and back; push with pbf or springs",
        .no_sculpt = "reads the bed once when it is made; sculpt with pbf or springs",
    };
}

}  // namespace

const SolverRegistry& SolverRegistry::builtin() {
    static const SolverRegistry registry = [] {
        SolverRegistry r;
        // kBuiltinSolverNames' order.
#ifndef METARIVER_NO_BULLET
        for (SolverEntry e : {springs_entry(), bullet_entry(), pbf_entry(), swe_entry(), hybrid_entry()}) (void)r.add(std::move(e));
#else
        for (SolverEntry e : {springs_entry(), pbf_entry(), swe_entry(), hybrid_entry()}) (void)r.add(std::move(e));
#endif
        return r;
    }();
    return registry;
}

Status SolverRegistry::add(SolverEntry entry) {
    if (entry.kind.name.empty()) return Error{"solver: a solver needs a name"};
    if (!entry.create) return Error{fmt::format("solver: \"{}\" has no factory", entry.kind.name)};
    if (find(entry.kind)) return Error{fmt::format("solver: \"{}\" is registered already", entry.kind.name)};
    entries_.push_back(std::move(entry));
    return Ok{};
}

Result<const SolverEntry*> SolverRegistry::find(SolverKind kind) const {
    const auto it = std::find_if(entries_.begin(), entries_.end(), [&](const SolverEntry& e) { return e.kind == kind; });
    if (it == entries_.end())
        return Error{fmt::format("solver: must be one of {} (got '{}'){}", names(), kind.name, left_out(kind))};
    return &*it;
}

std::string SolverRegistry::names() const {
    std::string s;
    for (const SolverEntry& e : entries_) s += fmt::format("{}\"{}\"", s.empty() ? "" : ", ", e.kind.name);
    return s;
}

}  // namespace mr
