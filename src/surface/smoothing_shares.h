// metariver surface, private: the smoothing's parallel passes over equal shares of an
// index range (src/surface/smoothing.cpp), each share's sums in a fixed order so the
// result does not depend on the thread count.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cstddef>

namespace mr::smoothing_shares {

inline double ms_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

/// The least number of elements worth splitting over the threads (on two busy cores a
/// parallel_for costs tens of microseconds).
constexpr size_t kMinSplit = 2048;
/// [0, n) in equal contiguous shares, one per thread when n is worth splitting (else
/// one); for passes that count per share and then fill from the counts' offsets, which
/// come out in element order whatever the number of shares.
struct Shares {
    static constexpr size_t kMax = 8;  ///< shares at most (callers keep per-share counts in arrays of it)
    size_t n = 0, count = 1;
    explicit Shares(size_t n_, size_t min_split = kMinSplit) : n(n_) {
        const size_t threads = static_cast<size_t>(std::max(1, tbb::this_task_arena::max_concurrency()));
        count = n < min_split ? 1 : std::min(threads, kMax);
    }
    size_t begin(size_t c) const { return n * c / count; }
    /// f(c, lo, hi) for every share c, in parallel (a blocked_range of shares: the one
    /// parallel_for form metariver calls, which the TSan build annotates).
    template <class F>
    void run(F&& f) const {
        if (count == 1) return f(size_t{0}, size_t{0}, n);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t c = r.begin(); c != r.end(); ++c) f(c, begin(c), begin(c + 1));
        });
    }
};

/// f(lo, hi) over [0, n) for work whose elements are independent (no sums): one equal
/// share per thread, so a few thousand vertices keep both cores busy (fixed chunks of
/// 4096 left 4,153 moving vertices as 4,096 + 57).
template <class F>
inline void for_split(size_t n, F&& f) {
    Shares(n).run([&](size_t, size_t lo, size_t hi) {
        if (lo < hi) f(lo, hi);
    });
}

}  // namespace mr::smoothing_shares
