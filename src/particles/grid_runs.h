// Parallel loops over a NeighborGrid's cell runs, shared by the PBF solver (pbf.cpp)
// and the diffuse particles (foam.cpp): each cell run's neighbour ranges (the 27 cells
// around it) are gathered once for all of its particles.
#pragma once

#include <metariver/neighbor_grid.h>

#include "parallel_blocks.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <cstdint>

namespace mr {

/// The index ranges [s[q], e[q]) of the cells around one cell run (at most 27).
struct Ranges {
    uint32_t s[27], e[27];
    int n = 0;
};

inline Ranges ranges_of(const NeighborGrid& g, size_t run) {
    Ranges rg;
    g.for_each_neighbor_range(run, [&](uint32_t s, uint32_t e) {
        rg.s[rg.n] = s;
        rg.e[rg.n] = e;
        ++rg.n;
    });
    return rg;
}

/// Calls f(i, ranges) for every binned index i (in sorted order), in parallel over
/// the cell runs; `ranges` are the neighbour ranges of i's cell run.
template <class F>
void for_each_run(const NeighborGrid& g, F&& f) {
    parallel_pass(tbb::blocked_range<size_t>(0, g.run_count(), 8), g.order().size(), [&](const tbb::blocked_range<size_t>& range) {
        for (size_t run = range.begin(); run != range.end(); ++run) {
            const Ranges rg = ranges_of(g, run);
            for (uint32_t i = g.run_start(run); i < g.run_start(run + 1); ++i) f(i, rg);
        }
    });
}

}  // namespace mr
