// One explicit stage of the shallow-water core (shallow_water.h) as a single sweep over the
// rows: each chunk of rows keeps a rolling window of three rows of velocities and surface,
// two rows of limited y slopes and two rows of y faces, so a cell's state is read from memory
// once per stage and nothing per cell but the new state is written back (no slope, face or
// velocity arrays). A face row shared by two chunks is computed by both from the same
// inputs: the result is the same on any number of threads.
#pragma once

#include <cstddef>
#include <cstdint>

namespace mr::swe {

enum class StageKind {
    Euler,       ///< out = U + dt L(U)
    HeunFirst,   ///< out = U + dt L(U), dry cells' discharges zeroed
    HeunSecond,  ///< out = (out + U + dt L(U)) / 2, where out holds Heun's starting state
};

struct StageIn {
    int nx = 0, ny = 0;
    size_t stride = 0;           ///< nx + 2: one ghost column each side, one ghost row each side
    const double* z = nullptr;   ///< bed
    const double *h = nullptr, *hu = nullptr, *hv = nullptr;  ///< the state, ghosts filled
    const int *lo = nullptr, *hi = nullptr;                    ///< active span per row
    double g = 9.81, dry = 1e-6;
    double r = 0.0;              ///< dt / dx
    double weight = 0.0;         ///< dt * dx: an edge face's flux to a volume
    bool second = false;         ///< MUSCL slopes (minmod of h, eta, u, v)
    /// Heun's stages: dt g n^2, each stage's new discharges slowed by the implicit Manning
    /// friction as in FinishRow (0: no friction; Euler leaves it to finish_row).
    double friction = 0.0;
    /// Reflective edges (x = 0, x = max, y = 0, y = max): at second order their faces see the
    /// mirror of the inner cell's reconstructed state, so that no water crosses them (the
    /// ghost cells, mirrors of the cells' centres, hold no slopes).
    bool wall_west = false, wall_east = false, wall_south = false, wall_north = false;
};

/// The end of a step on one row's columns [lo, hi]: rain (a rate per cell, or `rain` metres
/// everywhere), discharges zeroed at or below the dry depth, implicit Manning friction
/// q_new (1 + c |u_new| / h^(4/3)) = q with c = dt g n^2 (0: none, or done by Heun's stages).
struct FinishRow {
    double *h = nullptr, *hu = nullptr, *hv = nullptr;
    const double* rain_rate = nullptr;  ///< m/s per cell of the row, or nullptr: `rain`
    double rain = 0.0, dt = 0.0, c = 0.0, dry = 1e-6;
    int lo = 0, hi = -1;
};
struct StageOut {
    double *h = nullptr, *hu = nullptr, *hv = nullptr;
    /// Euler and HeunFirst write a scratch state: the columns each row wrote last time, so
    /// that the ones now outside the span are cleared (the scratch is zero where U is dry).
    int *dirty_lo = nullptr, *dirty_hi = nullptr;
    double *row_out = nullptr, *row_in = nullptr;  ///< per row: volume out of / into the edges
    uint64_t* row_clip = nullptr;                  ///< per row: negative depths clipped (added)
    /// Euler and HeunSecond: the end of the step done on each row as soon as it is written (its
    /// state, columns and rain rows filled in per row; rain_rate indexed like the state),
    /// with the rain added and the wet columns per row; nullptr: not done.
    const FinishRow* finish = nullptr;
    double* row_rain = nullptr;
    int *wet_lo = nullptr, *wet_hi = nullptr;
};

void run_stage(const StageIn& in, const StageOut& out, StageKind kind);

/// Returns the rain added (metres summed over the row's cells) and the row's wet columns.
double finish_row(const FinishRow& row, int& wet_lo, int& wet_hi);

/// The fastest wave max(|u|, |v|) + sqrt(g h) over the wet columns [lo, hi] of a row
/// (0 if none is wet), vectorised.
double row_wave_speed(const double* h, const double* hu, const double* hv, int lo, int hi, double g, double dry);

/// x^(1/3) for x > 0 (a bit estimate and three Halley steps, within 1e-15 of std::cbrt):
/// unlike std::cbrt it vectorises.
double cbrt_positive(double x);

}  // namespace mr::swe
