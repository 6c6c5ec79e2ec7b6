// metariver solver registry: every solver a scene can name (`solver = "pbf"`), in one
// place each: its name and help, its factory, its live-edit rule and the per-solver
// facts the Simulation asks about (the particles' scale, foam, the prefill, what it
// refuses). The Simulation looks its scene's solver up in a SolverRegistry and holds a
// copy of the entry; nothing else names a concrete solver type. SolverRegistry::builtin()
// has the three built-in solvers; a caller (a test, an embedding) copies it, adds its
// own and passes it to Simulation::create.
#pragma once

#include <metariver/core.h>
#include <metariver/solver.h>

#include <functional>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mr {

struct SceneDef;  // scene.h
class Terrain;    // terrain.h
class Bvh;        // terrain.h

/// A scene's `solver`: a name a SolverRegistry knows. Not an enum, so that a registry
/// can hold solvers this header does not list (SolverKind{"my-solver"}) and no code
/// switches over the built-in ones; compare with ==. The name must outlive every
/// SolverKind holding it (a string literal, or kBuiltinSolverNames).
struct SolverKind {
    std::string_view name;

    static const SolverKind Springs;  ///< the paper's own physics: gravity, springs, terrain collision
    static const SolverKind Bullet;   ///< the paper's engine physics (2.4) on Bullet: rigid spheres vs the terrain
    static const SolverKind Pbf;      ///< Position Based Fluids (Macklin and Mueller 2013) with the robust terrain collision
    static const SolverKind Swe;      ///< shallow water on the terrain's grid (swe_solver.h)
    static const SolverKind Hybrid;   ///< the grid and PBF particles where water leaves the ground (hybrid_solver.h)

    friend constexpr bool operator==(SolverKind a, SolverKind b) { return a.name == b.name; }
};

/// The built-in solvers' names, in the order of the `solver` key's choices (the order the
/// enum had: scene files and the viewer's list keep it).
inline constexpr std::string_view kBuiltinSolverNames[] = {"springs", "bullet", "pbf", "swe", "hybrid"};
inline constexpr SolverKind SolverKind::Springs{kBuiltinSolverNames[0]};
inline constexpr SolverKind SolverKind::Bullet{kBuiltinSolverNames[1]};
inline constexpr SolverKind SolverKind::Pbf{kBuiltinSolverNames[2]};
inline constexpr SolverKind SolverKind::Swe{kBuiltinSolverNames[3]};
inline constexpr SolverKind SolverKind::Hybrid{kBuiltinSolverNames[4]};

constexpr std::string_view to_string(SolverKind s) { return s.name; }
/// The index of `s` in kBuiltinSolverNames, -1 for a solver that is not built in.
constexpr int builtin_solver_index(SolverKind s) {
    for (size_t i = 0; i < std::size(kBuiltinSolverNames); ++i)
        if (kBuiltinSolverNames[i] == s.name) return static_cast<int>(i);
    return -1;
}

/// The scale of a solver's particles for Simulation::spray_fraction(), metres.
struct SprayScale {
    float spacing = 1.0f;        ///< rest spacing (airborne: more than 2 spacings above the ground)
    float kernel_radius = 2.0f;  ///< neighbourhood of the isolation test
};

/// One solver: what the Simulation needs to build, run and edit it.
struct SolverEntry {
    SolverKind kind;        ///< the scene's `solver` value
    std::string_view help;  ///< one line: what it simulates
    /// Builds the solver for a resolved scene (Simulation::def(): automatic values and
    /// the source's placement resolved) on the Simulation's terrain and tree, which
    /// outlive it. Required.
    std::function<std::unique_ptr<Solver>(const SceneDef& def, const Terrain& terrain, const Bvh& bvh)> create;
    /// Live edit (Simulation::apply): gives `solver` (one `create` made) the edited
    /// scene's values in place; false, and nothing changed, when they need a new solver
    /// (the particle budget changed). Null: the solver takes nothing in place (every key
    /// it reads asks for a rebuild before this is reached).
    std::function<bool(Solver& solver, const SceneDef& edited)> apply;
    /// The particles' scale for spray_fraction(); null: SprayScale{} (1 m, 2 m).
    std::function<SprayScale(const SceneDef& def)> spray_scale;
    /// [foam] runs on this solver's particles with this kernel radius (metres); null: no
    /// foam for this solver.
    std::function<float(const SceneDef& def)> foam_kernel_radius;
    /// particles.prefill fills a carved channel with this solver's particles (Solver::place
    /// at pbf.spacing) when the scene is created.
    bool prefills = false;
    /// Every particle is emitted from a pool and goes back to it when it sinks or leaves
    /// the terrain (PBF's lattice source): active = emitted - sunk - respawned. Otherwise
    /// a respawned particle is placed again at once (the progress report's balance).
    bool respawn_to_pool = false;
    /// Why Simulation::push() is refused, after "push: solver = \"NAME\" "; "": it is not.
    std::string_view no_push;
    /// Why Simulation::sculpt() is refused (and restore() does nothing), after
    /// "sculpt: solver = \"NAME\" "; "": terrain edits reach the water.
    std::string_view no_sculpt;
};

/// The solvers a Simulation may be created with, by name. A plain value: copy one, add
/// entries, pass it on.
class SolverRegistry {
public:
    /// springs, bullet, pbf (kBuiltinSolverNames' order; METARIVER_WITH_BULLET=OFF: no bullet). Built once, on first use.
    static const SolverRegistry& builtin();

    /// Adds a solver. Error (naming `solver`, nothing added) when its name is empty or
    /// already registered, or it has no factory.
    Status add(SolverEntry entry);
    /// The entry of solver `kind`; an unknown name is an error naming `solver` and the
    /// registered names.
    Result<const SolverEntry*> find(SolverKind kind) const;
    std::span<const SolverEntry> entries() const { return entries_; }
    /// The registered names, quoted, comma-separated ("\"springs\", \"bullet\", \"pbf\"").
    std::string names() const;

private:
    std::vector<SolverEntry> entries_;
};

}  // namespace mr
