// The head over a lake's spill level that passes a discharge out of it: the steady init's
// starting level for a lake on a river's route (swe.init = "steady", src/scene/swe_solver.cpp's
// fill_depressions). The lake's water leaves over its crest cells (the cells its water covers
// next to lower ground), each passing what the grid passes there, not the ideal
// weir: hydrostatic reconstruction (Audusse et al. 2004) sees the face between a deep lake cell
// and its crest cell as a Riemann problem between water at rest H deep (the lake's surface
// over the crest's bed) and the flow after the crest. Where that flow is critical or faster,
// the face passes Ritter's dam-break flux (8/27) sqrt(g) H^(3/2) = 0.928 H^(3/2) m^2/s, not
// the broad crest's 1.705 H^(3/2) (a lake settles 1.49 times the ideal weir's head, 1.50
// predicted); where it is Manning's uniform flow h deep, u = h^(2/3) sqrt(slope) / n on the
// bed's slope after the crest (slower than critical: the mild slopes of km cells), the
// rarefaction's invariant gives sqrt(g H) = sqrt(g h) + u / 2. tests/swe/lake_crest_test.cpp:
// a crest 5 cells wide over a chute and before a mild channel, the estimate 0.6 % under and
// 7.7 % over the head the lake settles at; the old estimate (one cell's ideal weir) 96 % and
// 52 % over.
#pragma once

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
    /// The lake's water reaches crests at most this many cells from it (4-neighbour steps
    /// along the way the flood reached them).
    /// Measured on random_1000x700 (1 m cells, flats of equal 16-bit heights at most spill
    /// points) against the levels four of its route's lakes settled to from above and from
    /// below in the spin-up: 8 cells gave 1.6-2.0 times their settled heads, no bound 0.5-0.6
    /// times (a lake's shallow margins reach crests the grid's water hardly gets to), 16 cells
    /// 0.95-1.06 times (a lake of 14 cells: 2.1). The crests of western_usa's lakes (8.3 km
    /// cells) lie within 3 cells.
    int most_steps = 16;
    /// route_lakes looks this far for the outlets that split a lake's outflow. On
    /// random_1000x700 the outlet by which a route lake of 1,261 cells feeds a side lake of
    /// 18,708 cells (off the flood's route; 0.144 m^3/s of the 0.373 went into it in the
    /// spin-up) lies beyond 16 cells: 64 sends it 0.13 m^3/s and nothing to a side lake the
    /// spin-up's water never reaches (256 sends that one 0.015).
    int route_steps = 64;
};

/// A cell over which a lake's water leaves.
struct Crest {
    int cell = 0;
    double sill = 0.0;   ///< metres: the lowest water level that reaches the cell from the lake (its bed, or a higher sill on the way)
    double slope = 0.0;  ///< the drop to its lowest neighbour below the spill level over dx; infinite: a free fall (the map's edge)
};

/// The crest cells of the lake whose cells are `lake` (all at spill level `spill`) under up to
/// `most_head` metres over it: the cells its water covers at that level (a priority flood from
/// the lake over the cells not below the spill level) next to a cell whose level is below
/// the spill level (the water runs on towards the route downstream without the lake), or on
/// the map's edge. The lake's shore, however low, is no crest where nothing lower lies beyond
/// it; a flat crest counts at its brink.
std::vector<Crest> find_crests(const CrestGrid& grid, std::span<const int> lake, double spill, double most_head);

/// What one crest passes per metre of width (m^2/s) under `head` metres of water over its
/// bed: Ritter's flux, or less where Manning's flow after it (n = `manning`, 0: none) is
/// slower than critical (see the top of this file).
double crest_flow(double head, double slope, double manning, double gravity);

/// The discharge (m^3/s) over `crests` with the water at `level`.
double crest_discharge(std::span<const Crest> crests, const CrestGrid& grid, double level);

/// The head h (metres over `spill`) at which the lake's crest passes `discharge` m^3/s
/// (bisection to 1e-9 of the head), over the crests under twice the head one cell's crest
/// would need; NaN where the lake has none.
double crest_head(const CrestGrid& grid, std::span<const int> lake, double spill, double discharge);

/// What each lake on the sources' way passes at the steady state, and its head.
struct LakeFlow {
    double inflow = 0.0;  ///< m^3/s
    double head = 0.0;    ///< metres over the spill level that passes it (crest_head; NaN: no crest)
};

/// The sources' discharge routed through the lakes (each a list of cells at one spill level,
/// `from` the priority flood's neighbour towards the edge per cell, -1 at the edge): each
/// start's `discharge` goes down its flood path into the first lake on it; the lakes, the
/// highest spill level first, pass what comes in over their crests (crest_head; then every
/// crest under that head within grid.route_steps cells), each crest its share (crest_flow
/// at the lake's head), down the flood path from the crest into the next lake, or off the
/// map (a lake without a crest: all of it down the flood path from its cells). A lake beside the route gets what its neighbours' crests send
/// it (random_1000x700: a side lake of 18,708 cells, off the flood's route, filled at 40 % of
/// the inflow for thousands of simulated seconds); one no crest feeds gets nothing.
std::vector<LakeFlow> route_lakes(const CrestGrid& grid, std::span<const std::vector<int>> lakes, std::span<const int> from,
                                  std::span<const int> starts, double discharge);

}  // namespace mr::swe
