// The "hybrid" solver (include/metariver/hybrid_solver.h): a SweSolver's grid and a
// PbfSolver's particles on one terrain, with water handed between them each frame.
#include <metariver/hybrid_solver.h>
#include <metariver/pbf_solver.h>
#include <metariver/terrain.h>

#include "shallow_water.h"

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>

namespace mr {

namespace {

// The four faces of a cell: +x, -x, +z, -z (core index i along x, j along z).
constexpr int kDi[4] = {1, -1, 0, 0};
constexpr int kDj[4] = {0, 0, 1, -1};

/// The particles' own source: none. A rate of 1e-9 particles/s (one particle in 30
/// years) keeps PBF's lattice source from emitting the budget (without a rate it owes the
/// whole pool) and sends a particle that leaves the terrain back to the pool.
SpawnDef no_source(Vec3 at, int budget) {
    SpawnDef s;
    s.count = std::max(budget, 1);
    s.center = at;
    s.half_extent = Vec3(0.5f);
    s.interval = 0;
    s.initial_velocity = Vec3(0.0f);
    s.flow_rate = 1e-9f;
    return s;
}

/// Least bend (drop / dx less the grade upstream) of a face that can launch.
constexpr float kMinBend = 0.01f;

/// The fractional part of x (x >= 0): the quasi-random sequences of the placements.
double frac(double x) { return x - std::floor(x); }

}  // namespace

HybridSolver::HybridSolver(const Terrain& terrain, const Bvh& bvh, const HybridDef& def, const SweDef& swe,
                           Vec3 resolved_source, const PbfDef& pbf, const CollisionDef& collision,
                           const IntegratorDef& integrator)
    : def_(def), gravity_(integrator.gravity) {
    grid_ = std::make_unique<SweSolver>(terrain, swe, resolved_source, integrator.gravity);
    pbf_ = std::make_unique<PbfSolver>(terrain, bvh, no_source(resolved_source, def.max_particles), pbf, collision,
                                       integrator, 1u, SinkDef{});
    particle_volume_ = double(pbf.spacing) * double(pbf.spacing) * double(pbf.spacing);
    const swe::ShallowWater& core = grid_->core();
    owed_.assign(static_cast<size_t>(core.nx()) * core.ny(), 0.0);
    sheds_.assign(owed_.size(), 0);
    rest_time_.assign(static_cast<size_t>(std::max(def.max_particles, 1)), 0.0f);
    counters_ = pbf_->counters();
    find_edges();
}

HybridSolver::~HybridSolver() = default;

const Particles* HybridSolver::water_particles() const { return pbf_->water_particles(); }
const HeightfieldWater* HybridSolver::water_heightfield() const { return grid_->water_heightfield(); }

std::vector<std::string> HybridSolver::warnings() const { return grid_->warnings(); }

bool HybridSolver::set_params(const HybridDef& def, const SweDef& swe, Vec3 resolved_source) {
    if (def.max_particles != def_.max_particles) return false;
    if (!grid_->set_params(swe, resolved_source)) return false;
    const bool new_drop = def.drop != def_.drop || def.min_grade != def_.min_grade || (def.launch > 0.0f) != (def_.launch > 0.0f);
    def_ = def;
    if (new_drop) find_edges();
    return true;
}

void HybridSolver::find_edges() {
    const swe::ShallowWater& core = grid_->core();
    edges_.clear();
    cliff_faces_ = launch_faces_ = 0;
    const auto inside = [&](int i, int j) { return i >= 0 && j >= 0 && i < core.nx() && j < core.ny(); };
    const double dx = core.dx();
    for (int j = 0; j < core.ny(); ++j)
        for (int i = 0; i < core.nx(); ++i) {
            EdgeCell e{i, j, 0, 0, {0.0f, 0.0f, 0.0f, 0.0f}};
            for (int d = 0; d < 4; ++d) {
                const int ni = i + kDi[d], nj = j + kDj[d], pi = i - kDi[d], pj = j - kDj[d];
                if (!inside(ni, nj)) continue;
                const double drop = core.bed(i, j) - core.bed(ni, nj);
                if (!(drop > def_.drop)) continue;
                const uint8_t bit = uint8_t(1u << d);
                if (drop >= double(def_.min_grade) * dx) {
                    e.faces |= bit, e.cliffs |= bit;
                    ++cliff_faces_;
                    continue;
                }
                // The grade the water arrives on, from the cell upstream (none at the map's edge).
                const double arrives = inside(pi, pj) ? (core.bed(pi, pj) - core.bed(i, j)) / dx : 0.0;
                e.bend[d] = static_cast<float>(drop / dx - arrives);
                // Convex by 1 % at least (a straight reach's round-off is not a bend; a 1 %
                // bend launches at 22 m/s on 1 m cells).
                if (def_.launch > 0.0f && e.bend[d] > kMinBend) e.faces |= bit, ++launch_faces_;
            }
            if (e.faces) edges_.push_back(e);
        }
    // A cell that cannot shed owes nothing and sheds nothing (what the every-cell scan
    // set each frame); one that still can keeps what it owes.
    std::vector<uint8_t> edge(owed_.size(), 0);
    for (const EdgeCell& e : edges_) edge[static_cast<size_t>(e.j) * core.nx() + e.i] = 1;
    for (size_t c = 0; c < owed_.size(); ++c)
        if (!edge[c]) owed_[c] = 0.0, sheds_[c] = 0;
}

double HybridSolver::exchange(int i, int j, double volume, double momentum_x, double momentum_z) {
    // The core's own exchange: counted in its balance (MassBalance::exchanged).
    return grid_->core().exchange(i, j, volume, momentum_x, momentum_z);
}

void HybridSolver::shed(float frame_dt) {
    const swe::ShallowWater& core = grid_->core();
    const double dx = core.dx(), area = dx * dx;
    const size_t free = pbf_->water().pool.free();
    size_t budget = free;
    // Only the cells find_edges() found: every other cell's owed_ and sheds_ stay 0.
    for (const EdgeCell& e : edges_) {
        const int i = e.i, j = e.j;
        const size_t c = static_cast<size_t>(j) * core.nx() + i;
        const double h = core.depth(i, j);
        if (h < def_.min_depth) {
            owed_[c] = 0.0;
            sheds_[c] = 0;
            continue;
        }
        const double vel[2] = {core.discharge_x(i, j) / h, core.discharge_y(i, j) / h};
        bool edge = false;
        for (int d = 0; d < 4; ++d) {
            if (!(e.faces & (1u << d))) continue;
            const double along = kDi[d] != 0 ? kDi[d] * vel[0] : kDj[d] * vel[1];
            if (along < def_.min_speed || !launches(e, d, along)) continue;
            edge = true;
            owed_[c] += along * h * dx * frame_dt;  // what flows over the face this frame
            const double whole = std::floor(std::min(owed_[c], core.depth(i, j) * area) / particle_volume_);
            const size_t n = std::min(static_cast<size_t>(std::max(whole, 0.0)), budget);
            if (n == 0) continue;
            owed_[c] -= double(n) * particle_volume_;
            budget -= n;
            shed_cell(i, j, d, double(n), frame_dt);
        }
        if (!edge) owed_[c] = 0.0;
        sheds_[c] = edge ? 1 : 0;
    }
}

bool HybridSolver::launches(const EdgeCell& e, int d, double along) const {
    if (e.cliffs & (1u << d)) return true;
    // A body thrown at `along` on the arriving grade falls (arrives dx + g dx^2 / (2 u^2))
    // over the cell; the bed falls by drop: it leaves the ground where the bed falls more.
    const double dx = grid_->core().dx();
    return 2.0 * along * along * double(e.bend[d]) >= double(def_.launch) * double(gravity_) * dx;
}

void HybridSolver::shed_cell(int i, int j, int dir, double count, float frame_dt) {
    swe::ShallowWater& core = grid_->core();
    const HeightfieldWater& w = *grid_->water_heightfield();
    const double h = core.depth(i, j), dx = core.dx();
    const double u = core.discharge_x(i, j) / h, v = core.discharge_y(i, j) / h;
    const double along_speed = kDi[dir] != 0 ? kDi[dir] * u : kDj[dir] * v;
    const float spacing = static_cast<float>(std::cbrt(particle_volume_));
    const Vec3 d(float(kDi[dir]), 0.0f, float(kDj[dir])), t(-d.z, 0.0f, d.x);
    const Vec3 base(w.origin.x + float(i) * w.spacing, float(core.bed(i, j)), w.origin.z + float(j) * w.spacing);
    const size_t n = static_cast<size_t>(count);
    new_pos_.clear();
    new_vel_.clear();
    double given[2] = {0.0, 0.0};
    for (size_t k = 0; k < n; ++k) {
        // Spread over the face (across, R2 sequence) and the water's height, and along the
        // flow by how far it went in the part of the frame since it was shed.
        const double s = double(shed_count_++);
        const double across = (frac(0.5 + s * 0.7548776662) - 0.5) * 0.9 * dx;
        const double up = frac(0.5 + s * 0.5698402910) * std::max(h - spacing, 0.0);
        const double ahead = 0.15 * dx + along_speed * frame_dt * (double(k) + 0.5) / double(n);
        new_pos_.push_back(base + d * float(ahead) + t * float(across) + Vec3(0.0f, 0.5f * spacing + float(up), 0.0f));
        new_vel_.emplace_back(float(u), 0.0f, float(v));
        given[0] += particle_volume_ * double(new_vel_.back().x);
        given[1] += particle_volume_ * double(new_vel_.back().z);
    }
    const double volume = count * particle_volume_;
    const double moved = -exchange(i, j, -volume, -volume * u, -volume * v);
    pbf_->place(new_pos_, new_vel_);
    stats_.to_particles += moved;
    stats_.particles_made += n;
    stats_.cell_momentum_out[0] += moved * u;
    stats_.cell_momentum_out[1] += moved * v;
    stats_.particle_momentum_in[0] += given[0];
    stats_.particle_momentum_in[1] += given[1];
}

void HybridSolver::absorb(float frame_dt) {
    swe::ShallowWater& core = grid_->core();
    const HeightfieldWater& w = *grid_->water_heightfield();
    ParticlePool& pool = pbf_->water().pool;
    Particles& p = pool.particles;
    const float spacing = static_cast<float>(std::cbrt(particle_volume_));
    for (size_t k = pool.next_to_activate; k-- > 0;) {
        const Vec3 x = p.position[k], vel = p.velocity[k];
        const int i = static_cast<int>(std::lround((x.x - w.origin.x) / w.spacing));
        const int j = static_cast<int>(std::lround((x.z - w.origin.z) / w.spacing));
        if (i < 0 || j < 0 || i >= core.nx() || j >= core.ny() || !std::isfinite(x.y)) continue;
        const double h = core.depth(i, j), ground = core.bed(i, j);
        const float age = float(pool.frame - p.birth_frame[k]) * frame_dt;
        float& rest = rest_time_[p.id[k] % rest_time_.size()];
        const bool on_ground = x.y <= ground + h + 2.0f * spacing;
        rest = on_ground && glm::length(vel) < def_.rest_speed ? rest + frame_dt : 0.0f;
        const bool landed = age >= def_.absorb_age && h >= def_.absorb_depth && x.y <= ground + h + 0.5f * spacing &&
                            !sheds_[static_cast<size_t>(j) * core.nx() + i];
        // Particles about to leave the terrain (the outer ring of cells, or under the bed)
        // go into the cell under them instead of being lost: the grid's open edges count
        // what leaves as outflow.
        const bool leaving = i == 0 || j == 0 || i == core.nx() - 1 || j == core.ny() - 1 || x.y < ground - spacing;
        if (!landed && !leaving && rest < def_.rest_time) continue;
        const double m[2] = {particle_volume_ * double(vel.x), particle_volume_ * double(vel.z)};
        exchange(i, j, particle_volume_, m[0], m[1]);
        stats_.to_grid += particle_volume_;
        ++stats_.particles_absorbed;
        stats_.particle_momentum_out[0] += m[0];
        stats_.particle_momentum_out[1] += m[1];
        stats_.cell_momentum_in[0] += m[0];
        stats_.cell_momentum_in[1] += m[1];
        rest = 0.0f;
        pbf_->deactivate(k);
    }
}

void HybridSolver::pump(float frame_dt) {
    if (!(def_.pump_rate > 0.0f)) return;
    swe::ShallowWater& core = grid_->core();
    const HeightfieldWater& w = *grid_->water_heightfield();
    const auto cell = [&](Vec3 p, int& i, int& j) {
        i = static_cast<int>(std::lround((p.x - w.origin.x) / w.spacing));
        j = static_cast<int>(std::lround((p.z - w.origin.z) / w.spacing));
        return i >= 0 && j >= 0 && i < core.nx() && j < core.ny();
    };
    int fi = 0, fj = 0, ti = 0, tj = 0;
    if (!cell(def_.pump_from, fi, fj) || !cell(def_.pump_to, ti, tj)) return;
    // The cells within the radius (the one under pump_from at least) and the water they hold.
    const int r = static_cast<int>(std::floor(def_.pump_radius / w.spacing));
    const double area = core.dx() * core.dx(), r2 = double(def_.pump_radius) * def_.pump_radius;
    const auto each = [&](auto f) {
        for (int j = std::max(0, fj - r); j <= std::min(core.ny() - 1, fj + r); ++j)
            for (int i = std::max(0, fi - r); i <= std::min(core.nx() - 1, fi + r); ++i) {
                const double ex = double(i - fi) * w.spacing, ez = double(j - fj) * w.spacing;
                if ((i != fi || j != fj) && ex * ex + ez * ez > r2) continue;
                if (core.depth(i, j) > 0.0) f(i, j, core.depth(i, j) * area);
            }
    };
    double held = 0.0;
    each([&](int, int, double v) { held += v; });
    const double want = std::min(double(def_.pump_rate) * double(frame_dt), held);
    if (!(want > 0.0)) return;
    double taken = 0.0;
    each([&](int i, int j, double v) {
        const double part = want * v / held, h = core.depth(i, j);
        taken -= exchange(i, j, -part, -part * core.discharge_x(i, j) / h, -part * core.discharge_y(i, j) / h);
    });
    stats_.pumped += exchange(ti, tj, taken, 0.0, 0.0);
}

void HybridSolver::step_frame(float frame_dt) {
    const bool ok = frame_dt > 0.0f && std::isfinite(frame_dt);
    if (ok) shed(frame_dt);
    // The grid's frame and the particles' frame read and write nothing of each other's (the
    // water crosses in shed() before and absorb() after), so they run side by side: the
    // grid's few rows (a serial 30-50 us on the waterfall) go to a second thread while this
    // one starts the particles, and with one thread they run one after the other. Each is
    // deterministic on its own, so the state is the same for any thread count.
    tbb::parallel_invoke([&] { pbf_->step_frame(frame_dt); },
                         [&] { grid_->advance_frame(frame_dt); });  // shown by refresh() below, after the absorbed water
    if (ok) absorb(frame_dt);
    if (ok) pump(frame_dt);
    grid_->refresh();
    const SolverCounters& c = pbf_->counters();
    stats_.lost += double(c.respawned - respawned_seen_) * particle_volume_;
    respawned_seen_ = c.respawned;
    counters_ = c;
    counters_.substeps = grid_->counters().substeps;
    counters_.cell_updates = grid_->counters().cell_updates;
    counters_.max_speed = std::max(c.max_speed, grid_->counters().max_speed);
    ++frame_;
}

double HybridSolver::grid_balance_error() const { return grid_->core().balance().error(); }

double HybridSolver::grid_outflow() const { return grid_->core().balance().outflow; }

double HybridSolver::total_volume() const {
    return grid_->core().volume() + double(pbf_->particles().active_count()) * particle_volume_;
}

std::array<double, 2> HybridSolver::total_momentum() const {
    const swe::ShallowWater& core = grid_->core();
    const double area = core.dx() * core.dx();
    std::array<double, 2> m{0.0, 0.0};
    for (int j = 0; j < core.ny(); ++j)
        for (int i = 0; i < core.nx(); ++i) {
            m[0] += core.discharge_x(i, j) * area;
            m[1] += core.discharge_y(i, j) * area;
        }
    const Particles& p = pbf_->particles();
    for (size_t k = 0; k < p.size(); ++k)
        if (p.active[k]) {
            m[0] += particle_volume_ * double(p.velocity[k].x);
            m[1] += particle_volume_ * double(p.velocity[k].z);
        }
    return m;
}

}  // namespace mr
