// Simulation's public methods over its state (simulation_impl.h): the work runs inside
// the Simulation's thread arena (set_threads), the accessors return references into it.
#include <metariver/hybrid_solver.h>
#include <metariver/scene.h>

#include "simulation_impl.h"

#include <fmt/format.h>
#include <tbb/info.h>

#include <algorithm>

namespace mr {

Simulation::Simulation(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Simulation::~Simulation() = default;

Status Simulation::set_threads(int n) {
    if (n < 0 || n > kMaxThreads)
        return Error{fmt::format("threads: must be in [0, {}] (0: every core; got {})", kMaxThreads, n)};
    Impl& m = *impl_;
    if (n == m.threads_) return Ok{};
    m.arena_.terminate();
    // No more slots than cores: TBB would warn that it cannot find the workers (and
    // could not run them at once anyway).
    m.arena_.initialize(n == 0 ? tbb::task_arena::automatic : std::min(n, tbb::info::default_concurrency()));
    m.threads_ = n;
    return Ok{};
}

int Simulation::threads() const { return impl_->threads_; }

void Simulation::step(float frame_dt) {
    impl_->run([&] { impl_->step(frame_dt); });
}
Result<ApplyResult> Simulation::apply(const SceneDef& next) {
    return impl_->run([&] { return impl_->apply(next); });
}
Result<TerrainEdit> Simulation::sculpt(const Brush& brush) {
    return impl_->run([&] { return impl_->sculpt(brush); });
}
void Simulation::restore(const TerrainEdit& edit) {
    impl_->run([&] { impl_->restore(edit); });
}
void Simulation::pour(const Vec3& center, int count) {
    impl_->run([&] { impl_->solver_->pour(center, count); });
}
Status Simulation::move_source(const Vec3& center) {
    return impl_->run([&] { return impl_->move_source(center); });
}
Result<size_t> Simulation::push(const Vec3& center, float radius, const Vec3& velocity) {
    return impl_->run([&] { return impl_->push(center, radius, velocity); });
}

uint64_t Simulation::terrain_lifts() const { return impl_->terrain_lifts_; }
const SceneDef& Simulation::requested() const { return impl_->requested_; }
const SceneDef& Simulation::def() const { return impl_->def_; }
const Terrain& Simulation::terrain() const { return impl_->terrain_; }
const Bvh& Simulation::bvh() const { return impl_->bvh_; }
const Particles& Simulation::particles() const { return impl_->particles(); }
const HeightfieldWater* Simulation::heightfield() const { return impl_->solver_->water_heightfield(); }
const SweSolver* Simulation::grid() const {
    if (const auto* h = dynamic_cast<const HybridSolver*>(impl_->solver_.get())) return &h->grid();
    return dynamic_cast<const SweSolver*>(impl_->solver_.get());
}
Status Simulation::set_rain(std::span<const float> mm_per_h) {
    SweSolver* g = dynamic_cast<SweSolver*>(impl_->solver_.get());
    if (auto* h = dynamic_cast<HybridSolver*>(impl_->solver_.get())) g = &h->grid();
    if (!g)
        return Error{fmt::format("solver = \"{}\" has no water grid to rain on (solver = \"swe\" and \"hybrid\" have one)",
                                 impl_->solver_entry_.kind.name)};
    return g->set_rain(mm_per_h);
}
const SolverEntry& Simulation::solver_entry() const { return impl_->solver_entry_; }
const Solver& Simulation::solver() const { return *impl_->solver_; }
const SolverCounters& Simulation::counters() const { return impl_->solver_->counters(); }
std::vector<std::string> Simulation::warnings() const { return impl_->warnings(); }
const ScalarGrid& Simulation::field() const { return impl_->field_; }
const SparseField& Simulation::sparse_field() const { return impl_->sparse_; }
std::array<int, 3> Simulation::field_dims() const { return impl_->field_dims(); }
const SurfaceMesh& Simulation::surface() const { return impl_->surface_; }
const SmoothingStats& Simulation::smoothing_stats() const { return impl_->smooth_ws_.stats; }
const FrameTimings& Simulation::last_timings() const { return impl_->timings_; }
const FoamSystem* Simulation::foam() const { return impl_->foam_ ? &*impl_->foam_ : nullptr; }
uint64_t Simulation::frame() const { return impl_->solver_->frame(); }
uint64_t Simulation::field_overflows() const { return impl_->field_overflows_; }
const std::string& Simulation::field_overflow_message() const { return impl_->field_overflow_message_; }
uint64_t Simulation::field_windows() const { return impl_->field_windows_; }
size_t Simulation::field_left_out() const { return impl_->field_left_out_; }
uint64_t Simulation::state_hash() const { return impl_->state_hash(); }
std::span<const Vec3> Simulation::last_exits() const { return impl_->solver_->last_exits(); }
const std::optional<RiverSize>& Simulation::sizing() const { return impl_->sizing_; }
size_t Simulation::prefilled() const { return impl_->prefilled_; }

// The channel's measures update the drainage network after a terrain edit: work, so in
// the arena.
const ChannelMap& Simulation::channel() const {
    return *impl_->run([&] { return &impl_->channel(); });
}
std::span<const std::pair<int, int>> Simulation::main_channel() const {
    impl_->run([&] { impl_->refresh_channel(); });
    return impl_->main_path_;
}
float Simulation::wet_fraction() const {
    return impl_->run([&] { return impl_->wet_fraction(); });
}
float Simulation::channel_coverage() const {
    return impl_->run([&] { return impl_->channel_coverage(); });
}
float Simulation::spray_fraction() const {
    return impl_->run([&] { return impl_->spray_fraction(); });
}

SceneView Simulation::view() const {
    const FoamSystem* f = foam();
    const DiffuseParticles* foam = f ? &f->particles() : impl_->heightfield_foam_ ? &impl_->heightfield_foam_->particles() : nullptr;
    if (f && impl_->heightfield_foam_) {  // the hybrid: the particles' spray and the grid's foam drawn together
        DiffuseParticles& both = impl_->foam_view_;
        both = f->particles();
        const DiffuseParticles& g = impl_->heightfield_foam_->particles();
        auto append = [](auto& to, const auto& from) { to.insert(to.end(), from.begin(), from.end()); };
        append(both.position, g.position);
        append(both.velocity, g.velocity);
        append(both.life, g.life);
        append(both.kind, g.kind);
        append(both.neighbours, g.neighbours);
        append(both.fluid_velocity, g.fluid_velocity);
        foam = &both;
    }
    return SceneView{.terrain = &impl_->terrain_,
                     .bvh = &impl_->bvh_,
                     .paper_rows = impl_->def_.terrain.paper_row_orientation,
                     .particles = &particles(),
                     .surface = &impl_->surface_,
                     .foam = foam,
                     .flow_radius = flow_radius(impl_->def_),
                     .surface_velocity = impl_->heightfield_velocity_,
                     .surface_grid_velocity = impl_->seam_velocity_,
                     .bodies = bodies(),
                     .owner = this,
                     .frame = frame()};
}

}  // namespace mr
