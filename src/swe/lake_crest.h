// The head over a lake's spill level that passes a discharge out of it: the steady init's
// starting level for a lake on a river's route (swe.init = "steady", src/scene/swe_solver.cpp's
// fill_depressions). The lake's water leaves over its crest cells (the cells next to it from
// which water runs on to lower ground), each passing what the grid passes there, not the ideal
// weir: hydrostatic reconstruction (Audusse et al. 2004) sees the face between a deep lake cell
// and its crest cell as a Riemann problem between water at rest H deep (the lake's surface
// over the crest's bed) and the flow after the crest. Where that flow is critical or faster,
// the face passes Ritter's dam-break flux (8/27) sqrt(g) H^(3/2) = 0.928 H^(3/2) m^2/s, not
// the broad crest's 1.705 H^(3/2) (a lake settles 1.49 times the ideal weir's head, 1.50
// predicted); where it is Manning's uniform flow h deep, u = h^(2/3) sqrt(slope) / n on the
// bed's slope after the crest (slower than critical: the mild slopes of km cells), the
// rarefaction's invariant gives sqrt(g H) = sqrt(g h) + u / 2. Measured in
// tests/swe/lake_crest_test.cpp: the one-cell ideal weir's head was 2.9x too low or high.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace mr::swe {

/// The grid a lake's crest is looked for on (row-major, index j * nx + i).
struct CrestGrid {
    int nx = 0, ny = 0;
    double dx = 1.0;                ///< cell size, metres
    std::span<const double> bed;    ///< bed elevation per cell, metres
    std::span<const double> level;  ///< the priority flood's spill level per cell, metres (>= bed)
    double manning = 0.0;           ///< Manning's n, s/m^(1/3); 0: no friction (the weir law alone)
    double gravity = 9.81;          ///< m/s^2
    double lake_depth = 1e-3;       ///< a cell is in a lake where its level stands this much over its bed, metres
};

/// A cell next to the lake over which its water leaves.
struct Crest {
    int cell = 0;
    double bed = 0.0;    ///< metres
    double slope = 0.0;  ///< the bed's slope downstream of the cell; infinite: a free fall (the map's edge)
};

/// The crest cells of the lake whose cells are `lake` (all at spill level `spill`): the cells
/// next to it, not in it, from which the water runs to a lower spill level (towards the
/// route downstream): those with a neighbour whose level is below `spill` (the slope: the
/// steepest such drop over dx), those on the map's edge, and those at the spill level whose
/// flat reaches such a cell within a few cells (the slope: the drop over the distance). A
/// shoreline cell whose water only runs back into the lake is no crest.
std::vector<Crest> find_crests(const CrestGrid& grid, std::span<const int> lake, double spill);

/// What one crest passes per metre of width (m^2/s) under `head` metres of water over its
/// bed: Ritter's flux, or less where Manning's flow after it (n = `manning`, 0: none) is
/// slower than critical (see the top of this file).
double crest_flow(double head, double slope, double manning, double gravity);

/// The discharge (m^3/s) over `crests` with the water at `level`.
double crest_discharge(std::span<const Crest> crests, const CrestGrid& grid, double level);

/// The head h (metres over `spill`) at which the lake's crest passes `discharge` m^3/s
/// (bisection to 1e-9 of the head); NaN where the lake has no crest.
double crest_head(const CrestGrid& grid, std::span<const int> lake, double spill, double discharge);

}  // namespace mr::swe
