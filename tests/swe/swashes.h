// SWASHES' analytic solutions (Delestre, Lucas, Ksinant, Darboux, Laguerre, Vo, James, Cordier
// 2013, "SWASHES: a compilation of shallow water analytic solutions for hydraulic and
// environmental studies", Int. J. Numer. Meth. Fluids 72(3), arXiv:1110.0288), written from
// the paper's formulas, and the error norms the tests and the docs' table report.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace swashes {

constexpr double kG = 9.81;

/// The bump of sections 3.1.1 and 3.1.2 (lake at rest, flows over a bump): 25 m long.
inline double bump(double x) { return x > 8.0 && x < 12.0 ? 0.2 - 0.05 * (x - 10.0) * (x - 10.0) : 0.0; }

struct Sample {
    double h = 0.0, u = 0.0;
};

/// Stoker's dam break on a wet bed (4.1.1): hl at x < x0, hr after, flat frictionless bed.
struct Stoker {
    double hl = 0.005, hr = 0.001, x0 = 5.0;
    double cm = 0.0;
    Stoker() {
        // -8 g hr cm^2 (sqrt(g hl) - cm)^2 + (cm^2 - g hr)^2 (cm^2 + g hr) = 0, cm in
        // (sqrt(g hr), sqrt(g hl)), by bisection; its root satisfies the shock's
        // Rankine-Hugoniot relation with the rarefaction's u = 2 (sqrt(g hl) - cm), which
        // Swashes.StokerRootSatisfiesRankineHugoniot checks.
        auto f = [&](double c) {
            const double c2 = c * c, d = std::sqrt(kG * hl) - c;
            return -8.0 * kG * hr * c2 * d * d + (c2 - kG * hr) * (c2 - kG * hr) * (c2 + kG * hr);
        };
        double a = std::sqrt(kG * hr), b = std::sqrt(kG * hl);
        for (int k = 0; k < 200; ++k) {
            const double m = 0.5 * (a + b);
            (f(a) * f(m) <= 0.0 ? b : a) = m;
        }
        cm = 0.5 * (a + b);
    }
    Sample at(double x, double t) const {
        const double cl = std::sqrt(kG * hl);
        const double xa = x0 - t * cl, xb = x0 + t * (2.0 * cl - 3.0 * cm);
        const double xc = x0 + t * (2.0 * cm * cm * (cl - cm)) / (cm * cm - kG * hr);
        if (x <= xa) return {hl, 0.0};
        if (x <= xb) {
            const double s = cl - (x - x0) / (2.0 * t);
            return {4.0 / (9.0 * kG) * s * s, 2.0 / 3.0 * ((x - x0) / t + cl)};
        }
        if (x <= xc) return {cm * cm / kG, 2.0 * (cl - cm)};
        return {hr, 0.0};
    }
};

/// Ritter's dam break on a dry bed (4.1.2).
struct Ritter {
    double hl = 0.005, x0 = 5.0;
    Sample at(double x, double t) const {
        const double cl = std::sqrt(kG * hl);
        const double xa = x0 - t * cl, xb = x0 + 2.0 * t * cl;
        if (x <= xa) return {hl, 0.0};
        if (x <= xb) {
            const double s = cl - (x - x0) / (2.0 * t);
            return {4.0 / (9.0 * kG) * s * s, 2.0 / 3.0 * ((x - x0) / t + cl)};
        }
        return {0.0, 0.0};
    }
};

/// The root of h^3 + (z - e) h^2 + q^2 / (2 g) = 0 (Bernoulli at discharge q, head e) on
/// the subcritical (above critical depth) or supercritical branch, by bisection.
inline double bernoulli_depth(double q, double e, double z, bool subcritical) {
    const double hc = std::cbrt(q * q / kG);
    auto f = [&](double h) { return h * h * h + (z - e) * h * h + q * q / (2.0 * kG); };
    double a = subcritical ? hc : 1e-9, b = subcritical ? std::max(e - z, hc) + 1.0 : hc;
    for (int k = 0; k < 200; ++k) {
        const double m = 0.5 * (a + b);
        ((f(a) < 0.0) == (f(m) < 0.0) ? a : b) = m;
    }
    return 0.5 * (a + b);
}

/// Subcritical flow over the bump (3.1.3): q = 4.42 m^2/s, h = 2 m downstream.
inline double bump_subcritical(double x, double q = 4.42, double h_out = 2.0) {
    const double e = q * q / (2.0 * kG * h_out * h_out) + h_out;
    return bernoulli_depth(q, e, bump(x), true);
}

/// Transcritical flow without shock (3.1.4): q = 1.53 m^2/s, critical at the bump's top.
inline double bump_transcritical(double x, double q = 1.53) {
    const double hc = std::cbrt(q * q / kG);
    const double e = q * q / (2.0 * kG * hc * hc) + hc + 0.2;
    return bernoulli_depth(q, e, bump(x), x < 10.0);
}

/// Thacker's planar surface in a paraboloid (4.2.2): L = 4 m, a = 1 m, h0 = 0.1 m, eta = 0.5.
struct Thacker {
    double l = 4.0, a = 1.0, h0 = 0.1, eta = 0.5;
    double omega() const { return std::sqrt(2.0 * kG * h0) / a; }
    double bed(double x, double y) const {
        const double r2 = (x - l / 2) * (x - l / 2) + (y - l / 2) * (y - l / 2);
        return -h0 * (1.0 - r2 / (a * a));
    }
    double depth(double x, double y, double t) const {
        const double w = omega();
        const double s = eta * h0 / (a * a) * (2.0 * (x - l / 2) * std::cos(w * t) + 2.0 * (y - l / 2) * std::sin(w * t) - eta);
        return std::max(s - bed(x, y), 0.0);
    }
};

/// L1, L2 and Linf of an error sampled on cells of `cell_measure` (dx or dx^2).
struct Norms {
    double l1 = 0.0, l2 = 0.0, linf = 0.0;
};
inline Norms norms(const std::vector<double>& err, double cell_measure) {
    Norms n;
    for (double e : err) {
        n.l1 += std::abs(e) * cell_measure;
        n.l2 += e * e * cell_measure;
        n.linf = std::max(n.linf, std::abs(e));
    }
    n.l2 = std::sqrt(n.l2);
    return n;
}

}  // namespace swashes
