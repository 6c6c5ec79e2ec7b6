// Test support: the optional parts of this build (CMake's METARIVER_WITH_* options,
// docs/getting-started.md). A test of a part the build leaves out checks its refusal or
// skips; the default build has every part, and there the tests demand it. A file that
// includes this header is named in tests/CMakeLists.txt where METARIVER_NO_BULLET is
// defined (the definition reaches those files only).
#pragma once

namespace mr::test {

/// METARIVER_WITH_BULLET: the "bullet" solver is in SolverRegistry::builtin().
#ifdef METARIVER_NO_BULLET
inline constexpr bool kWithBullet = false;
#else
inline constexpr bool kWithBullet = true;
#endif

}  // namespace mr::test
