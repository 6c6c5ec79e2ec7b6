// The face flux of the shallow-water core (shallow_water.h): HLL on Audusse's hydrostatic
// reconstruction. Header-only so that the tests can check it on single faces.
#pragma once

#include <algorithm>
#include <cmath>

namespace mr::swe {

/// One side of a face: reconstructed depth, normal and transverse velocity, bed (metres, m/s).
struct FaceState {
    double h = 0.0, un = 0.0, ut = 0.0, z = 0.0;
};

/// The flux through a face, per metre of face: mass (m^2/s), the normal momentum as the
/// minus and the plus cell see it (they differ by Audusse's pressure correction), and the
/// transverse momentum.
struct FaceFlux {
    double mass = 0.0, mom_minus = 0.0, mom_plus = 0.0, trans = 0.0;
};

/// HLL flux of two depth-positive states (Einfeldt's speeds; a dry side takes the
/// rarefaction's front u -/+ 2c of the wet one). Branch-free (selects), so that a loop of
/// faces vectorises; both sides dry: no flux.
inline void hll(double hl, double ul, double vl, double hr, double ur, double vr, double g, double out[3]) {
    const double cl = std::sqrt(g * hl), cr = std::sqrt(g * hr);
    const double sl_wet = std::min(ul - cl, ur - cr), sr_wet = std::max(ul + cl, ur + cr);
    const double sl_rdry = hr <= 0.0 ? ul - cl : sl_wet, sr_rdry = hr <= 0.0 ? ul + 2.0 * cl : sr_wet;
    const double sl = hl <= 0.0 ? ur - 2.0 * cr : sl_rdry, sr = hl <= 0.0 ? ur + cr : sr_rdry;
    const double fl[3] = {hl * ul, hl * ul * ul + 0.5 * g * hl * hl, hl * ul * vl};
    const double fr[3] = {hr * ur, hr * ur * ur + 0.5 * g * hr * hr, hr * ur * vr};
    const double ul3[3] = {hl, hl * ul, hl * vl}, ur3[3] = {hr, hr * ur, hr * vr};
    const double inv = 1.0 / (sr - sl);  // sr == sl only where a select below drops it
    const double wet = hl + hr;          // depths are >= 0: 0 when both sides are dry
    for (int k = 0; k < 3; ++k) {
        const double mid = (sr * fl[k] - sl * fr[k] + sl * sr * (ur3[k] - ul3[k])) * inv;
        const double right = sr <= 0.0 ? fr[k] : mid;
        const double f = sl >= 0.0 ? fl[k] : right;
        out[k] = wet <= 0.0 ? 0.0 : f;
    }
}

/// Audusse et al. 2004: both sides' depths cut at the higher bed, the HLL flux of the cut
/// states, and each side's pressure correction g/2 (h^2 - h*^2).
inline FaceFlux hydrostatic_flux(const FaceState& l, const FaceState& r, double g) {
    const double zs = std::max(l.z, r.z);
    const double hl = std::max(0.0, l.h + l.z - zs), hr = std::max(0.0, r.h + r.z - zs);
    double f[3];
    hll(hl, l.un, l.ut, hr, r.un, r.ut, g, f);
    return {f[0], f[1] + 0.5 * g * (l.h * l.h - hl * hl), f[1] + 0.5 * g * (r.h * r.h - hr * hr), f[2]};
}

/// The smaller of a and b in magnitude when they share a sign, else 0 (branch-free: the
/// half sum of their signs times the smaller magnitude).
inline double minmod(double a, double b) {
    return 0.5 * (std::copysign(1.0, a) + std::copysign(1.0, b)) * std::min(std::abs(a), std::abs(b));
}

}  // namespace mr::swe
