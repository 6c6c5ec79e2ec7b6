// The size of the long simulation tests (ctest label `long`: tunneling_tests and
// water_tests). METARIVER_LONG_SCALE in (0, 1] is the share of their work to run: the
// default suite leaves it unset (1, the full size); the asan test preset sets 0.25 (a
// quarter of the particles, or of the frames where the particle count is what a test is
// about), so that CI runs every long test under ASan + UBSan through the same code paths
// in a few minutes (docs/reliability.md, "Sanitizers"; preset asan-long-full runs them at
// full size). A test whose checks do not hold at a smaller size runs at full size, or
// runs those checks at full size only, and says why.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

namespace mr::test {

/// METARIVER_LONG_SCALE, or 1 when unset. A value that is not a number in (0, 1] stops
/// the test program: a typo must not quietly run the full size or nothing.
inline double long_scale() {
    static const double scale = [] {
        const char* text = std::getenv("METARIVER_LONG_SCALE");
        if (!text || !*text) return 1.0;
        char* end = nullptr;
        const double v = std::strtod(text, &end);
        if (end == text || *end != '\0' || !std::isfinite(v) || v <= 0.0 || v > 1.0) {
            std::fprintf(stderr, "METARIVER_LONG_SCALE: must be a number in (0, 1] (got '%s')\n", text);
            std::exit(2);
        }
        std::printf("note: METARIVER_LONG_SCALE=%g: the long tests run at that share of their full size\n", v);
        return v;
    }();
    return scale;
}

/// `n` scaled, at least `at_least`.
inline int scaled(int n, int at_least = 1) {
    return std::max(at_least, static_cast<int>(std::lround(double(n) * long_scale())));
}

/// Whether this run is the full size (the checks that need the full length run then).
inline bool full_size() { return long_scale() >= 1.0; }

}  // namespace mr::test
