// A log-log line plot as SVG text: decade ticks (1, 2, 5 x 10^k) on both axes, one
// polyline with point markers per series, a legend, an optional reference line.
#include "bench_plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr::app {

namespace {

constexpr double kWidth = 720, kHeight = 440;
constexpr double kLeft = 70, kRight = 210, kTop = 40, kBottom = 60;  // margins; the legend sits on the right

std::string escape(const std::string& s) {
    std::string o;
    for (char c : s) {
        if (c == '&') o += "&amp;";
        else if (c == '<') o += "&lt;";
        else if (c == '>') o += "&gt;";
        else o += c;
    }
    return o;
}

std::string tick_label(double v) {
    if (v >= 1000.0) return v >= 1e6 ? fmt::format("{:g}M", v / 1e6) : fmt::format("{:g}k", v / 1e3);
    return fmt::format("{:g}", v);
}

/// Log axis from lo to hi (both > 0), widened to whole 1-2-5 steps.
struct LogAxis {
    double lo, hi;
    LogAxis(double a, double b) {
        lo = std::pow(10.0, std::floor(std::log10(a)));
        hi = std::pow(10.0, std::ceil(std::log10(b)));
        if (hi <= lo) hi = lo * 10.0;
    }
    double frac(double v) const { return (std::log10(v) - std::log10(lo)) / (std::log10(hi) - std::log10(lo)); }
    std::vector<double> ticks() const {
        std::vector<double> t;
        for (double d = lo; d <= hi * 1.0001; d *= 10.0)
            for (double m : {1.0, 2.0, 5.0})
                if (d * m <= hi * 1.0001) t.push_back(d * m);
        return t;
    }
};

}  // namespace

std::string plot_svg(const PlotDef& def) {
    double x0 = std::numeric_limits<double>::max(), x1 = 0, y0 = std::numeric_limits<double>::max(), y1 = 0;
    for (const PlotSeries& s : def.series)
        for (auto [x, y] : s.points)
            if (x > 0 && y > 0 && std::isfinite(x) && std::isfinite(y)) {
                x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
            }
    std::string svg = fmt::format(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} {1}\" "
        "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"{0}\" height=\"{1}\" fill=\"white\"/>\n"
        "<text x=\"{2}\" y=\"22\" font-size=\"14\" font-weight=\"bold\">{3}</text>\n",
        kWidth, kHeight, kLeft, escape(def.title));
    if (x1 <= 0) return svg + fmt::format("<text x=\"{}\" y=\"{}\">no data</text>\n</svg>\n", kLeft, kHeight / 2);
    if (def.budget_ms > 0) y0 = std::min(y0, def.budget_ms), y1 = std::max(y1, def.budget_ms);
    const LogAxis ax(x0, x1), ay(y0, y1);
    const double pw = kWidth - kLeft - kRight, ph = kHeight - kTop - kBottom;
    const auto px = [&](double x) { return kLeft + ax.frac(x) * pw; };
    const auto py = [&](double y) { return kTop + (1.0 - ay.frac(y)) * ph; };
    for (double t : ax.ticks())
        svg += fmt::format("<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#ddd\"/>"
                           "<text x=\"{0:.1f}\" y=\"{3}\" text-anchor=\"middle\">{4}</text>\n",
                           px(t), kTop, kTop + ph, kTop + ph + 16, tick_label(t));
    for (double t : ay.ticks())
        svg += fmt::format("<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#ddd\"/>"
                           "<text x=\"{3}\" y=\"{4:.1f}\" text-anchor=\"end\">{5}</text>\n",
                           kLeft, py(t), kLeft + pw, kLeft - 6, py(t) + 4, tick_label(t));
    svg += fmt::format("<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#444\"/>\n", kLeft, kTop,
                       pw, ph);
    svg += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", kLeft + pw / 2, kHeight - 18,
                       escape(def.x_label));
    svg += fmt::format("<text transform=\"translate(18 {}) rotate(-90)\" text-anchor=\"middle\">{}</text>\n",
                       kTop + ph / 2, escape(def.y_label));
    if (def.budget_ms > 0)
        svg += fmt::format("<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#c00\" "
                           "stroke-dasharray=\"2 4\"/><text x=\"{3}\" y=\"{4:.1f}\" fill=\"#c00\">{5}</text>\n",
                           kLeft, py(def.budget_ms), kLeft + pw, kLeft + 4, py(def.budget_ms) - 4,
                           escape(def.budget_label));
    int legend = 0;
    for (const PlotSeries& s : def.series) {
        std::vector<std::pair<double, double>> pts;
        for (auto p : s.points)
            if (p.first > 0 && p.second > 0 && std::isfinite(p.first) && std::isfinite(p.second)) pts.push_back(p);
        if (pts.empty()) continue;
        std::sort(pts.begin(), pts.end());
        const std::string dash = s.dashed ? " stroke-dasharray=\"6 3\"" : "";
        std::string line;
        for (auto [x, y] : pts) line += fmt::format("{:.1f},{:.1f} ", px(x), py(y));
        svg += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"{}/>\n", line,
                           s.color, dash);
        for (auto [x, y] : pts)
            svg += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3\" fill=\"{}\"><title>{}: {:g} particles, "
                               "{:.2f} ms</title></circle>\n",
                               px(x), py(y), s.color, escape(s.name), x, y);
        const double ly = kTop + 8 + 20 * legend++;
        svg += fmt::format("<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"{3}\" "
                           "stroke-width=\"2\"{4}/><text x=\"{5}\" y=\"{6:.1f}\">{7}</text>\n",
                           kLeft + pw + 12, ly, kLeft + pw + 36, s.color, dash, kLeft + pw + 42, ly + 4,
                           escape(s.name));
    }
    return svg + "</svg>\n";
}

}  // namespace mr::app
