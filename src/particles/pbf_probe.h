// The PBF solver's test hooks (not a user's API, so not in include/metariver): the twin
// tests reach its density sums and switch its neighbour lists through here, by the
// solver's state (pbf_state.h), which the public header declares opaque.
#pragma once

#include <metariver/pbf_solver.h>

#include "pbf_state.h"

#include <vector>

namespace mr {

struct PbfProbe {
    /// Number density of every particle through the grid (after sort_by_cell) and by
    /// brute force over all active pairs.
    static void densities(PbfSolver& s, std::vector<float>& out) { pbf_densities(s.water(), s.def().kernel_radius, out); }
    static void densities_brute_force(const PbfSolver& s, std::vector<float>& out) {
        pbf_densities_brute_force(s.water(), s.def().kernel_radius, out);
    }
    /// Passes through per-particle neighbour lists built once per step (true, the
    /// default) or through the 27 cells around each particle's cell (false: the slow
    /// twin; the same pairs in the same order, so the same result bit for bit). `skin`:
    /// the lists' reach beyond h, as a fraction of h (a smaller skin rebuilds more often).
    static void set_neighbor_lists(PbfSolver& s, bool on, float skin = kPbfListSkin) {
        PbfSolver::State::of(s).pbf_lists_on_ = on;
        PbfSolver::State::of(s).pbf_list_skin_ = skin;
    }
    /// The list passes' sums eight entries at a time with AVX2 (true, the default, where
    /// the CPU has it: pbf_simd.h) or one at a time (false: their twin, the same pairs and
    /// formulas, summed in another order).
    static void set_simd(PbfSolver& s, bool on) { PbfSolver::State::of(s).pbf_simd_on_ = on; }
    /// The lists of the latest step (their builds() counts rebuilds too).
    static const NeighborLists& neighbor_lists(const PbfSolver& s) { return PbfSolver::State::of(s).pbf_lists_; }
    /// The water meets the bodies (true, the default) or does not see them (false: the
    /// bodies fall through it, and SolverCounters::inside_bodies counts what they cover).
    static void set_body_coupling(PbfSolver& s, bool on) { PbfSolver::State::of(s).body_coupling_on_ = on; }
    /// The terrain's share of a kernel centred at `x` and its gradient (PbfDef::wall_density).
    static float wall_share(const PbfSolver& s, const Vec3& x, Vec3& grad) {
        return pbf_terrain_share(s.water().collider.terrain(), s.def().kernel_radius, x, grad);
    }
};

}  // namespace mr
