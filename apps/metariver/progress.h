// A progress bar on one terminal line (stderr), for the commands that write frames.
#pragma once

namespace mr::app {

/// True when stderr is a terminal and a job of `total` steps is long enough for a bar.
bool progress_wanted(bool enabled, long long total);
/// Draws "[#####.....] 12/60 frames, 3.1 fps, 15 s left" over the current line.
void print_progress(long long done, long long total, double elapsed_s);
/// Ends the bar's line (call before printing anything else).
void end_progress();

}  // namespace mr::app
