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
};

struct StageOut {
    double *h = nullptr, *hu = nullptr, *hv = nullptr;
    /// Euler and HeunFirst write a scratch state: the columns each row wrote last time, so
    /// that the ones now outside the span are cleared (the scratch is zero where U is dry).
    int *dirty_lo = nullptr, *dirty_hi = nullptr;
    double *row_out = nullptr, *row_in = nullptr;  ///< per row: volume out of / into the edges
    uint64_t* row_clip = nullptr;                  ///< per row: negative depths clipped (added)
};

void run_stage(const StageIn& in, const StageOut& out, StageKind kind);

}  // namespace mr::swe
