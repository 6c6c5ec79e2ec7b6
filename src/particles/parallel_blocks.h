// The particle passes' parallel loop: a few thousand particles or fewer split into one
// contiguous piece per thread, more into the balancing scheduler's blocks.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <cstddef>

namespace mr {

/// Up to this many particles a pass splits its range into one piece per thread
/// (tbb::static_partitioner): each thread then takes the same particles in every pass of a
/// step, so their arrays stay in its core's cache, and a pass costs one task per thread.
/// The hybrid's waterfall (about 500 particles, 2 threads) ran its PBF step in 121 us instead
/// of 214 us a substep this way, where its two vCPUs lay far apart on the host (a cache
/// line took 150-190 ns from one to the other): the balancing blocks moved between the
/// threads from pass to pass and each pass read what the other core had written. Above
/// it the balancing blocks stay (a big river's dense and sparse cells differ in cost).
inline constexpr size_t kStaticPassMax = 4096;

/// tbb::parallel_for(range, body), statically split when the pass covers at most
/// kStaticPassMax particles. Every caller's body writes only its own indices, so the
/// result does not depend on the split.
template <class Range, class Body>
void parallel_pass(const Range& range, size_t particles, const Body& body) {
    if (particles <= kStaticPassMax)
        tbb::parallel_for(range, body, tbb::static_partitioner());
    else
        tbb::parallel_for(range, body);
}

}  // namespace mr
