// The plot `metariver bench` writes next to its JSON: milliseconds per frame (or step)
// against particle count, log-log, one polyline per series, as a hand-written SVG (no
// plotting dependency): people look at it in docs/benchmarks.md rather than read tables.
#pragma once

#include <string>
#include <vector>

namespace mr::app {

struct PlotSeries {
    std::string name;                          ///< legend text
    std::string color;                         ///< SVG colour, e.g. "#1f77b4"
    bool dashed = false;                       ///< peers dashed, ours solid
    std::vector<std::pair<double, double>> points;  ///< (particles, ms), both > 0; sorted by x when drawn
};

struct PlotDef {
    std::string title;
    std::string x_label = "particles";
    std::string y_label = "ms per frame (median)";
    std::vector<PlotSeries> series;
    double budget_ms = 0.0;  ///< a horizontal reference line (e.g. 16.7 ms = 60 fps); 0 = none
    std::string budget_label;
};

/// The SVG document (width 720, height 440). Series without points, and points with
/// x <= 0 or y <= 0 (nothing on a log axis), are left out; with no point at all the
/// plot says so instead of drawing axes over nothing.
std::string plot_svg(const PlotDef& def);

}  // namespace mr::app
