// Test support: what a test needs from outside the repository, and the switch that turns
// a skip for a missing file or tool into a failure (METARIVER_REQUIRE_ALL=1, set by
// .ci/run), so nothing silently stops being tested where everything should be there.
//
// The real DEM crops (ETOPO5, public domain) live in the repository (assets/heightmaps/real):
// tests load them without a check. The paper's own heightmaps (no licence stated) stay
// outside, in METARIVER_SHARED_DIR/heightmaps/metawater; only tests of those files may skip.
#pragma once

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <string_view>

namespace mr::test {

/// METARIVER_REQUIRE_ALL=1: every file and tool a test names must be there.
inline bool require_all() {
    const char* v = std::getenv("METARIVER_REQUIRE_ALL");
    return v != nullptr && std::string_view(v) == "1";
}

/// A real DEM crop in the repository (assets/heightmaps/real/NAME, e.g. "alps.png").
inline std::string real_dem(std::string_view name) {
    return std::string(METARIVER_SOURCE_DIR) + "/assets/heightmaps/real/" + std::string(name);
}

/// One of the paper's heightmaps (METARIVER_SHARED_DIR/heightmaps/metawater/NAME).
inline std::string paper_map(std::string_view name) {
    return std::string(METARIVER_SHARED_DIR) + "/heightmaps/metawater/" + std::string(name);
}

/// Whether `path` exists; where it does not and METARIVER_REQUIRE_ALL=1, a (non-fatal)
/// failure names it. For loops over optional files that go on without the missing one.
inline bool have_file(const std::string& path) {
    if (std::filesystem::exists(path)) return true;
    if (require_all()) ADD_FAILURE() << "METARIVER_REQUIRE_ALL=1 and " << path << " is missing";
    return false;
}

}  // namespace mr::test

/// Skips the test with `msg` (a stream expression), or fails it where METARIVER_REQUIRE_ALL=1.
#define MR_SKIP_OR_FAIL(msg)                                                                   \
    do {                                                                                       \
        if (::mr::test::require_all()) {                                                       \
            GTEST_FAIL() << "METARIVER_REQUIRE_ALL=1, and this test would have skipped: " << msg; \
        } else {                                                                               \
            GTEST_SKIP() << msg;                                                               \
        }                                                                                      \
    } while (0)
