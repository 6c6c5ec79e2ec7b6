#include "progress.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <string>
#include <unistd.h>

namespace mr::app {

bool progress_wanted(bool enabled, long long total) { return enabled && total >= 10 && isatty(STDERR_FILENO); }

void print_progress(long long done, long long total, double elapsed_s) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(kWidth * done / std::max(total, 1LL));
    const double fps = elapsed_s > 0.0 ? static_cast<double>(done) / elapsed_s : 0.0;
    const double eta = fps > 0.0 ? static_cast<double>(total - done) / fps : 0.0;
    fmt::print(stderr, "\r[{}{}] {}/{} frames, {:.1f} fps, {:.0f} s left   ", std::string(static_cast<size_t>(filled), '#'),
               std::string(static_cast<size_t>(kWidth - filled), '.'), done, total, fps, eta);
    std::fflush(stderr);
}

void end_progress() { fmt::print(stderr, "\n"); }

}  // namespace mr::app
