// Simulation's state (the Pimpl behind include/metariver/scene.h): the scene, the terrain,
// the solver, and the scratch and caches one frame reuses (balls, field, surface
// workspaces, the drainage network). Not part of the library's API: simulation.cpp,
// simulation_edit.cpp and simulation_api.cpp share it.
#pragma once

#include <metariver/scene.h>

#include "heightfield_foam.h"

#include <tbb/task_arena.h>

#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace mr {

class GridBodies;  // rigid_bodies_grid.h
class PbfSolver;   // pbf_solver.h
/// Deletes the grid's bodies (simulation_bodies.cpp, where GridBodies is complete).
struct GridBodiesDelete {
    void operator()(GridBodies* b) const;
};

struct Simulation::Impl {
    /// Builds the source, the field's settings, the solver, the foam and the prefill
    /// (the solver is null when the entry's factory built none: create() reports it).
    Impl(const SceneDef& def, Terrain terrain, Bvh bvh, std::optional<RiverSize> sizing, SolverEntry solver);

    SceneDef def_;
    SceneDef requested_;
    Terrain terrain_;
    Bvh bvh_;
    SolverEntry solver_entry_;
    std::unique_ptr<Solver> solver_;
    Particles no_particles_;  ///< particles() of a solver without particles
    std::vector<Vec3> balls_;
    ScalarGrid field_;
    SparseField sparse_;
    SparseFieldDef sparse_def_;
    SurfaceWorkspace surface_ws_;
    SmoothingWorkspace smooth_ws_;
    SurfaceMesh surface_;
    HeightfieldScratch heightfield_scratch_;  ///< append_heightfield_surface's
    std::vector<glm::vec4> seam_velocity_;  ///< the grid's velocity and share at the field's vertices (seam_grid_velocities)
    std::vector<uint32_t> seam_scratch_;  ///< drop_under_water's
    HeightfieldSeam seam_;  ///< where the field draws the heightfield's water (hybrid: join_heightfield_to_field)
    std::vector<Vec3> heightfield_velocity_;  ///< the velocity at the heightfield's vertices (the mesh's last)
    FrameTimings timings_;
    uint64_t field_overflows_ = 0;
    uint64_t field_windows_ = 0;  ///< frames whose field left particles out (keep_balls_within_cap)
    size_t field_left_out_ = 0;   ///< the most it left out in a frame
    uint64_t terrain_lifts_ = 0;
    std::string field_overflow_message_;
    // The drainage network and what is measured on it; updated when read after a
    // terrain edit (refresh_channel()) over the samples changed since (empty: current).
    struct SampleRect {
        int i0 = std::numeric_limits<int>::max(), i1 = -1, j0 = std::numeric_limits<int>::max(), j1 = -1;
        bool empty() const { return i1 < i0 || j1 < j0; }
    };
    mutable ChannelMap channel_;
    mutable std::vector<std::pair<int, int>> main_path_;
    mutable ChannelCoverage coverage_;
    mutable SampleRect channel_stale_;
    std::optional<RiverSize> sizing_;
    std::optional<FoamSystem> foam_;
    std::optional<HeightfieldFoam> heightfield_foam_;  ///< [foam] on a heightfield solver's water
    size_t prefilled_ = 0;
    /// Every piece of work runs inside it (Simulation::set_threads): its concurrency
    /// bounds the threads the solver, the field and the surface use.
    mutable tbb::task_arena arena_;
    int threads_ = 0;  ///< Simulation::threads()

    /// Runs `f` inside the arena (its parallel loops use at most threads() threads).
    template <class F>
    decltype(auto) run(F&& f) const {
        return arena_.execute(std::forward<F>(f));
    }

    const Particles& particles() const {
        const Particles* p = solver_->water_particles();
        return p ? *p : no_particles_;
    }
    const ChannelMap& channel() const {
        refresh_channel();
        return channel_;
    }

    void step(float frame_dt);
    Result<ApplyResult> apply(const SceneDef& next);
    Status move_source(const Vec3& center);
    Result<size_t> push(const Vec3& center, float radius, const Vec3& velocity);
    Result<TerrainEdit> sculpt(const Brush& brush);
    void restore(const TerrainEdit& edit);
    std::vector<std::string> warnings() const;
    std::array<int, 3> field_dims() const;
    float wet_fraction() const;
    float spray_fraction() const;
    float channel_coverage() const;
    uint64_t state_hash() const;
    // Bodies (simulation_bodies.cpp).
    Status add_scene_bodies(const std::vector<BodyDef>& bodies);
    Status replace_bodies(const std::vector<BodyDef>& bodies);
    std::span<const BodyState> bodies() const;
    /// Who holds the bodies: PBF's solver (two-way coupled), else, for a solver whose water
    /// is a heightfield (swe, hybrid), grid_bodies_ (made here when first asked); null and
    /// null: this solver has none.
    struct BodyHost {
        PbfSolver* pbf = nullptr;
        GridBodies* grid = nullptr;
        explicit operator bool() const { return pbf || grid; }
        Result<uint32_t> add(const BodyDef& def) const;
        Status remove(uint32_t id) const;
        Status set_motion(uint32_t id, const Vec3& position, const glm::quat& orientation, const Vec3& velocity,
                          const Vec3& angular_velocity) const;
    };
    BodyHost body_host();
    /// The bodies on the grid's water, one frame (after the solver's step).
    void step_grid_bodies(float frame_dt);
    std::unique_ptr<GridBodies, GridBodiesDelete> grid_bodies_;
    /// The ids of the bodies made from def_.bodies, in the list's order (replace_bodies).
    std::vector<uint32_t> scene_body_ids_;

    void prefill_channel();
    float prefill_share() const;
    void configure_field();
    /// The foam's step on the latest frame's particles ([foam]).
    void step_foam(float frame_dt);
    /// [foam]'s systems for this solver: the particles' (FoamSystem), the grid's
    /// (HeightfieldFoam), or both (hybrid); none when foam.enabled is false.
    void make_foam();
    /// The hybrid's two foams in one list for SceneView (rebuilt by view()).
    mutable DiffuseParticles foam_view_;
    /// field -> marching cubes -> smoothing over `p` into surface_ (cleared first).
    void build_particle_surface(const Particles& p);
    /// The heightfield's triangle grid appended to surface_.
    void append_heightfield(const HeightfieldWater& w);
    void after_terrain_edit(const TerrainEdit& edit);
    /// main_path_ and coverage_ from the source at def_.spawn.center (`asked`: the source as
    /// the scene gave it, which says whether it follows the main head).
    void measure_main_channel(const SpawnDef& asked) const;
    /// Builds the drainage network and measures the main channel again when a terrain
    /// edit left them stale.
    void refresh_channel() const;
};

}  // namespace mr
