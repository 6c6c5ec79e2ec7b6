// One stage of the shallow-water core as one sweep over the rows (swe_stage.h).
#include "swe_stage.h"

#include "swe_flux.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <cmath>
#include <utility>
#include <vector>

namespace mr::swe {

namespace {

#define MR_RESTRICT __restrict__
// The column loops read rolling row buffers and write others (or the state rows): never the
// same memory, which the compiler cannot prove; ivdep lets it vectorise them.
#if defined(__GNUC__) && !defined(__clang__)
#define MR_IVDEP _Pragma("GCC ivdep")
#elif defined(__clang__)
#define MR_IVDEP _Pragma("clang loop vectorize(assume_safety)")
#else
#define MR_IVDEP
#endif

/// Row buffers of one chunk, indexed by column + 1 (ghost columns at 0 and nx + 1).
struct Scratch {
    size_t width = 0;
    std::vector<double> mem;
    double* prim[3][3];  // ring by row: u, v, eta
    double* sx[4];       // this row's x half slopes (half the limited slope): h, eta, u, v
    double* sy[2][4];    // ring by row: y half slopes
    double* fx[4];       // this row's x faces: mass, momentum minus / plus, transverse
    double* fy[2][4];    // ring by face row
    double* neg;         // this row's clipped depths

    void resize(int nx) {
        const size_t w = static_cast<size_t>(nx) + 2;
        if (w == width) return;
        width = w;
        mem.assign(w * 34, 0.0);  // zero: ghost columns' slopes stay 0
        double* p = mem.data();
        auto take = [&] { return std::exchange(p, p + w) + 1; };
        for (auto& row : prim)
            for (auto& b : row) b = take();
        for (auto& b : sx) b = take();
        for (auto& row : sy)
            for (auto& b : row) b = take();
        for (auto& b : fx) b = take();
        for (auto& row : fy)
            for (auto& b : row) b = take();
        neg = take();
    }
};

/// Restrict views of the row buffers, so that the loops over columns vectorise.
struct Prims {
    explicit Prims(double* const* p) : u(p[0]), v(p[1]), eta(p[2]) {}
    const double *MR_RESTRICT u, *MR_RESTRICT v, *MR_RESTRICT eta;
};
struct Slopes {
    explicit Slopes(double* const* s) : h(s[0]), eta(s[1]), u(s[2]), v(s[3]) {}
    const double *MR_RESTRICT h, *MR_RESTRICT eta, *MR_RESTRICT u, *MR_RESTRICT v;
};
struct Faces {
    explicit Faces(double* const* f) : mass(f[0]), minus(f[1]), plus(f[2]), trans(f[3]) {}
    double *MR_RESTRICT mass, *MR_RESTRICT minus, *MR_RESTRICT plus, *MR_RESTRICT trans;
    void put(int i, const FaceFlux& f) {
        mass[i] = f.mass;
        minus[i] = f.mom_minus;
        plus[i] = f.mom_plus;
        trans[i] = f.trans;
    }
};

inline double cbrt_estimate(double x) {
    uint64_t b;
    std::memcpy(&b, &x, sizeof b);
    const uint32_t hi = static_cast<uint32_t>(b >> 32) / 3u + 715094163u;  // fdlibm's cbrt B1
    const uint64_t yb = static_cast<uint64_t>(hi) << 32;
    double y;
    std::memcpy(&y, &yb, sizeof y);
    for (int k = 0; k < 3; ++k) {  // Halley: 5 -> 15 -> 45 -> 53 bits
        const double y3 = y * y * y;
        y = y * (y3 + 2.0 * x) / (2.0 * y3 + x);
    }
    return y;
}

/// Manning's implicit friction over a step, q_new (1 + c |q_new| / h^(7/3)) = q (c = dt g n^2),
/// as the divisor q / q_new = (1 + sqrt(1 + 4x)) / 2 with x = c |q| / h^(7/3), for a cell
/// holding (h, qx, qy), h taken at least `floor` (a depth the friction can divide by). Unlike
/// the semi-implicit 1 + x (|u| taken before the friction), its steady state does not depend
/// on dt: with the semi-implicit form and friction in each of Heun's stages the default
/// valley held 1 % more water at cfl 0.45 than at 0.05.
inline double manning_divisor(double h, double qx, double qy, double c, double floor) {
    const double hs = std::max(h, floor);
    const double speed = std::sqrt(qx * qx + qy * qy) / hs;
    const double x = c * speed / (hs * cbrt_estimate(hs));
    return 0.5 * (1.0 + std::sqrt(1.0 + 4.0 * x));
}

/// 0 where a cell lies in a trench along a direction: both neighbours' beds (zm, zp) rise
/// above the cell's (zc) by more than half its depth h, so that both faces cut its column
/// (a pit behind a crest, between dry banks); 1 elsewhere (its MUSCL slopes kept). In a
/// trench the limiter has no neighbour that pins the surface's slope: it took the step of
/// the surface down to the thin sheet over the outlet's crest as a tilt across the whole
/// cell, and Audusse's centred bed-slope term drove the whole column with it (western_usa
/// at 8.3 km cells: a 103 m deep pit pumped 4 m above its lake, a burst over its crest, the
/// outflow 0.73-1.26 of the inflow from window to window). First order there; a shoreline
/// cell (one neighbour wet and below) keeps its slopes.
inline double smooth_bed(double zm, double zc, double zp, double h) {
    return std::min(zm, zp) - zc > 0.5 * h ? 0.0 : 1.0;
}

/// Half of minmod(a, b) (swe_flux.h), which the faces take (c +/- s/2): the same bits as
/// 0.5 * minmod(a, b) for finite a and b (a sign select and an exact halving instead of the
/// sum of two signs and two products).
inline double half_minmod(double a, double b) {
    const double m = std::copysign(0.5 * std::min(std::abs(a), std::abs(b)), a);
    uint64_t ba, bb;  // the sign bits compared as integers (vectorises, signbit does not)
    std::memcpy(&ba, &a, sizeof ba);
    std::memcpy(&bb, &b, sizeof bb);
    return static_cast<int64_t>(ba ^ bb) < 0 ? 0.0 : m;
}

/// A reflective wall's outside state: the same depth and bed, the normal velocity reversed.
FaceState mirror(const FaceState& s) { return {s.h, -s.un, s.ut, s.z}; }

int ring3(int r) { return ((r % 3) + 3) % 3; }
int ring2(int r) { return ((r % 2) + 2) % 2; }

template <bool Second, StageKind Kind>
class Sweep {
public:
    Sweep(const StageIn& in, const StageOut& out, Scratch& s) : in_(in), out_(out), s_(s) {}

    void rows(int j0, int j1) {
        if (Second) {
            for (int r = j0 - 2; r <= j0; ++r) prims(r);
            slopes_y(j0 - 1);
            prims(j0 + 1);
            slopes_y(j0);
        } else {
            prims(j0 - 1);
            prims(j0);
        }
        faces_y(j0);
        for (int j = j0; j < j1; ++j) {
            if (Second) {
                prims(j + 2);
                slopes_y(j + 1);
            } else {
                prims(j + 1);
            }
            faces_y(j + 1);
            row(j);
        }
    }

private:
    bool empty(int j) const { return j < 0 || j >= in_.ny || in_.hi[j] < in_.lo[j]; }
    size_t at(int i, int r) const { return static_cast<size_t>(r + 1) * in_.stride + static_cast<size_t>(i + 1); }

    /// Row r's velocities and surface over the columns its own and its neighbours' spans read.
    void prims(int r) {
        if (r < -1 || r > in_.ny) return;
        int a = INT_MAX, b = INT_MIN;
        for (int s = r - 1; s <= r + 1; ++s)
            if (!empty(s)) {
                a = std::min(a, in_.lo[s]);
                b = std::max(b, in_.hi[s]);
            }
        if (a > b) return;
        a = std::max(a - 2, -1);
        b = std::min(b + 2, in_.nx);
        const size_t k0 = at(0, r);
        const double *MR_RESTRICT h = in_.h + k0, *MR_RESTRICT hu = in_.hu + k0, *MR_RESTRICT hv = in_.hv + k0,
                     *MR_RESTRICT z = in_.z + k0;
        double *MR_RESTRICT u = s_.prim[ring3(r)][0], *MR_RESTRICT v = s_.prim[ring3(r)][1], *MR_RESTRICT eta = s_.prim[ring3(r)][2];
        const double dry = in_.dry;
        MR_IVDEP
        for (int i = a; i <= b; ++i) {
            const double hh = h[i];
            const double d = std::max(hh, dry);  // divide always (vectorises), keep where wet
            const double uu = hu[i] / d, vv = hv[i] / d;
            u[i] = hh > dry ? uu : 0.0;
            v[i] = hh > dry ? vv : 0.0;
            eta[i] = hh + z[i];
        }
    }

    /// Row r's limited y slopes over its span and one column beyond (zero on ghost rows).
    void slopes_y(int r) {
        double* const* out = s_.sy[ring2(r)];
        if (r < 0 || r >= in_.ny) {
            for (int q = 0; q < 4; ++q) std::fill_n(out[q] - 1, s_.width, 0.0);
            return;
        }
        if (empty(r)) return;
        const int a = std::max(in_.lo[r] - 1, 0), b = std::min(in_.hi[r] + 1, in_.nx - 1);
        const double *MR_RESTRICT hs = in_.h + at(0, r - 1), *MR_RESTRICT hc = in_.h + at(0, r), *MR_RESTRICT hn = in_.h + at(0, r + 1);
        const double *MR_RESTRICT zs = in_.z + at(0, r - 1), *MR_RESTRICT zc = in_.z + at(0, r), *MR_RESTRICT zn = in_.z + at(0, r + 1);
        const Prims ps(s_.prim[ring3(r - 1)]), pc(s_.prim[ring3(r)]), pn(s_.prim[ring3(r + 1)]);
        double *MR_RESTRICT o0 = out[0], *MR_RESTRICT o1 = out[1], *MR_RESTRICT o2 = out[2], *MR_RESTRICT o3 = out[3];
        MR_IVDEP
        for (int i = a; i <= b; ++i) {
            const double keep = smooth_bed(zs[i], zc[i], zn[i], hc[i]);
            o0[i] = keep * half_minmod(hc[i] - hs[i], hn[i] - hc[i]);
            o1[i] = keep * half_minmod(pc.eta[i] - ps.eta[i], pn.eta[i] - pc.eta[i]);
            o2[i] = keep * half_minmod(pc.u[i] - ps.u[i], pn.u[i] - pc.u[i]);
            o3[i] = keep * half_minmod(pc.v[i] - ps.v[i], pn.v[i] - pc.v[i]);
        }
    }

    /// Face row f (between rows f - 1 and f): computed where both rows are active (the edge
    /// rows: where the row inside is), zero over the rest of either row's span.
    void faces_y(int f) {
        if (f < 0 || f > in_.ny) return;
        const bool below = !empty(f - 1), above = !empty(f);
        if (!below && !above) return;
        double* const* out = s_.fy[f % 2];
        int ulo = INT_MAX, uhi = INT_MIN;
        for (int r : {f - 1, f})
            if (!empty(r)) {
                ulo = std::min(ulo, in_.lo[r]);
                uhi = std::max(uhi, in_.hi[r]);
            }
        int ylo, yhi;
        if (f == 0 || f == in_.ny) {
            const int r = f == 0 ? 0 : in_.ny - 1;
            ylo = in_.lo[r];
            yhi = in_.hi[r];
        } else {
            ylo = below && above ? std::max(in_.lo[f - 1], in_.lo[f]) : 1;
            yhi = below && above ? std::min(in_.hi[f - 1], in_.hi[f]) : 0;
        }
        auto zero = [&](int a, int b) {
            for (int q = 0; q < 4 && a <= b; ++q) std::fill(out[q] + a, out[q] + b + 1, 0.0);
        };
        if (yhi < ylo) {
            zero(ulo, uhi);
            return;
        }
        zero(ulo, ylo - 1);
        zero(yhi + 1, uhi);
        const size_t ks = at(0, f - 1), kn = at(0, f);
        const double *MR_RESTRICT hs = in_.h + ks, *MR_RESTRICT hn = in_.h + kn, *MR_RESTRICT zs = in_.z + ks,
                     *MR_RESTRICT zn = in_.z + kn;
        const Prims ps(s_.prim[ring3(f - 1)]), pn(s_.prim[ring3(f)]);
        const Slopes ss(s_.sy[ring2(f - 1)]), sn(s_.sy[ring2(f)]);
        Faces o(out);
        const double g = in_.g;
        MR_IVDEP
        for (int i = ylo; i <= yhi; ++i) {
            // The cell below seen from its top (+0.5 slope), the cell above from its bottom;
            // normal velocity v, transverse u.
            FaceState a{hs[i], ps.v[i], ps.u[i], 0.0}, b{hn[i], pn.v[i], pn.u[i], 0.0};
            double ea = hs[i] + zs[i], eb = hn[i] + zn[i];
            if (Second) {
                a = {hs[i] + ss.h[i], ps.v[i] + ss.v[i], ps.u[i] + ss.u[i], 0.0};
                b = {hn[i] - sn.h[i], pn.v[i] - sn.v[i], pn.u[i] - sn.u[i], 0.0};
                ea += ss.eta[i];
                eb -= sn.eta[i];
            }
            a.z = ea - a.h;
            b.z = eb - b.h;
            o.put(i, hydrostatic_flux(a, b, g));
        }
        const bool south = f == 0 && in_.wall_south, north = f == in_.ny && in_.wall_north;
        if (!Second || !(south || north)) return;  // first order: the ghosts are the mirrors already
        // The inner row's state at the edge face (normal velocity v), against its mirror.
        const double* hr = south ? hn : hs;
        const double* zr = south ? zn : zs;
        const Prims& pr = south ? pn : ps;
        const Slopes& sr = south ? sn : ss;
        const double side = south ? -1.0 : 1.0;
        for (int i = ylo; i <= yhi; ++i) {
            const double hf = hr[i] + side * sr.h[i];
            const double etaf = hr[i] + zr[i] + side * sr.eta[i];
            const FaceState in{hf, pr.v[i] + side * sr.v[i], pr.u[i] + side * sr.u[i], etaf - hf};
            o.put(i, south ? hydrostatic_flux(mirror(in), in, g) : hydrostatic_flux(in, mirror(in), g));
        }
    }

    void slopes_x(int j, const double* MR_RESTRICT h, const double* MR_RESTRICT z, const Prims& p) {
        const int a = std::max(in_.lo[j] - 1, 0), b = std::min(in_.hi[j] + 1, in_.nx - 1);
        double *MR_RESTRICT o0 = s_.sx[0], *MR_RESTRICT o1 = s_.sx[1], *MR_RESTRICT o2 = s_.sx[2], *MR_RESTRICT o3 = s_.sx[3];
        MR_IVDEP
        for (int i = a; i <= b; ++i) {
            const double keep = smooth_bed(z[i - 1], z[i], z[i + 1], h[i]);
            o0[i] = keep * half_minmod(h[i] - h[i - 1], h[i + 1] - h[i]);
            o1[i] = keep * half_minmod(p.eta[i] - p.eta[i - 1], p.eta[i + 1] - p.eta[i]);
            o2[i] = keep * half_minmod(p.u[i] - p.u[i - 1], p.u[i + 1] - p.u[i]);
            o3[i] = keep * half_minmod(p.v[i] - p.v[i - 1], p.v[i + 1] - p.v[i]);
        }
    }

    void faces_x(int j, const double* MR_RESTRICT h, const double* MR_RESTRICT z, const Prims& p) {
        const Slopes sx(s_.sx);
        Faces o(s_.fx);
        const double g = in_.g;
        const int a0 = in_.lo[j], a1 = in_.hi[j] + 1;
        MR_IVDEP
        for (int i = a0; i <= a1; ++i) {
            FaceState a{h[i - 1], p.u[i - 1], p.v[i - 1], 0.0}, b{h[i], p.u[i], p.v[i], 0.0};
            double ea = h[i - 1] + z[i - 1], eb = h[i] + z[i];
            if (Second) {
                a = {h[i - 1] + sx.h[i - 1], p.u[i - 1] + sx.u[i - 1], p.v[i - 1] + sx.v[i - 1], 0.0};
                b = {h[i] - sx.h[i], p.u[i] - sx.u[i], p.v[i] - sx.v[i], 0.0};
                ea += sx.eta[i - 1];
                eb -= sx.eta[i];
            }
            a.z = ea - a.h;
            b.z = eb - b.h;
            o.put(i, hydrostatic_flux(a, b, g));
        }
        if (!Second) return;  // first order: the ghosts are the mirrors already
        // Column i's state at its face on `side` (+1: towards +x).
        auto state = [&](int i, double side) {
            const double hf = h[i] + side * sx.h[i];
            const double etaf = h[i] + z[i] + side * sx.eta[i];
            return FaceState{hf, p.u[i] + side * sx.u[i], p.v[i] + side * sx.v[i], etaf - hf};
        };
        if (in_.wall_west && a0 == 0) {
            const FaceState b = state(0, -1.0);
            o.put(0, hydrostatic_flux(mirror(b), b, g));
        }
        if (in_.wall_east && a1 == in_.nx) {
            const FaceState a = state(in_.nx - 1, 1.0);
            o.put(in_.nx, hydrostatic_flux(a, mirror(a), g));
        }
    }

    /// The edges' volume through row j's faces, outward positive.
    void tally(int j, double* const* fs, double* const* fn) {
        double o = 0.0, n = 0.0;
        auto add = [&](double outward) { (outward > 0.0 ? o : n) += std::abs(outward); };
        const int lo = in_.lo[j], hi = in_.hi[j];
        if (lo == 0) add(-s_.fx[0][0]);
        if (hi == in_.nx - 1) add(s_.fx[0][in_.nx]);
        if (j == 0)
            for (int i = lo; i <= hi; ++i) add(-fs[0][i]);
        if (j == in_.ny - 1)
            for (int i = lo; i <= hi; ++i) add(fn[0][i]);
        out_.row_out[j] = o * in_.weight;
        out_.row_in[j] = n * in_.weight;
    }

    /// Clears the scratch state's columns of row j that the last write left outside [lo, hi].
    void clear_stale(int j, int lo, int hi) {
        const int dlo = out_.dirty_lo[j], dhi = out_.dirty_hi[j];
        const size_t k0 = at(0, j);
        for (int i = dlo; i <= dhi; ++i)
            if (i < lo || i > hi) out_.h[k0 + i] = out_.hu[k0 + i] = out_.hv[k0 + i] = 0.0;
        out_.dirty_lo[j] = lo;
        out_.dirty_hi[j] = hi;
    }

    void row(int j) {
        constexpr bool scratch = Kind != StageKind::HeunSecond;
        if (empty(j)) {
            if (scratch) clear_stale(j, 0, -1);
            out_.row_out[j] = out_.row_in[j] = 0.0;
            if (out_.finish) finish(j, 0, -1);
            return;
        }
        const int lo = in_.lo[j], hi = in_.hi[j];
        const size_t k0 = at(0, j);
        const double *MR_RESTRICT h = in_.h + k0, *MR_RESTRICT hu = in_.hu + k0, *MR_RESTRICT hv = in_.hv + k0,
                     *MR_RESTRICT z = in_.z + k0;
        const Prims p(s_.prim[ring3(j)]);
        if (Second) slopes_x(j, h, z, p);
        faces_x(j, h, z, p);
        double* const* fs_rows = s_.fy[j % 2];
        double* const* fn_rows = s_.fy[(j + 1) % 2];
        tally(j, fs_rows, fn_rows);
        if (scratch) clear_stale(j, lo, hi);
        const Faces fx(s_.fx), fs(fs_rows), fn(fn_rows);
        const Slopes sx(s_.sx), sy(s_.sy[ring2(j)]);
        double *MR_RESTRICT oh = out_.h + k0, *MR_RESTRICT ou = out_.hu + k0, *MR_RESTRICT ov = out_.hv + k0;
        const double r = in_.r, g2 = 2.0 * in_.g, dry = in_.dry, c = in_.friction, floor = std::max(dry, 1e-12);
        double* MR_RESTRICT neg = s_.neg;  // 1 where a depth was clipped (counted after)
        MR_IVDEP
        for (int i = lo; i <= hi; ++i) {
            double hn = h[i] - r * (fx.mass[i + 1] - fx.mass[i] + fn.mass[i] - fs.mass[i]);
            double qx = hu[i] - r * (fx.minus[i + 1] - fx.plus[i] + fn.trans[i] - fs.trans[i]);
            double qy = hv[i] - r * (fn.minus[i] - fs.plus[i] + fx.trans[i + 1] - fx.trans[i]);
            if (Second) {
                // Audusse's centred bed-slope term of the second order.
                // (The slopes are stored halved: -2g h is 2 (-g h) exactly, the same bits.)
                qx += r * (-g2 * h[i] * (sx.eta[i] - sx.h[i]));
                qy += r * (-g2 * h[i] * (sy.eta[i] - sy.h[i]));
            }
            if (Kind != StageKind::Euler) {
                // Each of Heun's stages is an Euler step of the fluxes and the friction, so
                // that the second stage starts from the first's slowed discharges: friction
                // applied only after the average let a stage accelerate a thin film on a
                // steep km cell for a whole step and drain more than the cell held.
                const double f = manning_divisor(hn, qx, qy, c, floor);
                qx /= f;
                qy /= f;
            }
            if (Kind == StageKind::HeunSecond) {
                // Heun's average may hold an intermediate negative depth: only the average
                // is clipped (clipping the intermediate created its half as water).
                const double avg = 0.5 * (oh[i] + hn);
                neg[i] = avg < 0.0 ? 1.0 : 0.0;
                oh[i] = avg < 0.0 ? 0.0 : avg;
                ou[i] = 0.5 * (ou[i] + qx);
                ov[i] = 0.5 * (ov[i] + qy);
            } else {
                neg[i] = hn < 0.0 ? 1.0 : 0.0;
                hn = hn < 0.0 ? 0.0 : hn;
                if (Kind == StageKind::HeunFirst) {
                    qx = hn <= dry ? 0.0 : qx;
                    qy = hn <= dry ? 0.0 : qy;
                }
                oh[i] = hn;
                ou[i] = qx;
                ov[i] = qy;
            }
        }
        uint64_t clip = 0;
        for (int i = lo; i <= hi; ++i) clip += neg[i] != 0.0;
        out_.row_clip[j] += clip;
        if (out_.finish) finish(j, lo, hi);
    }

    /// The end of the step on row j while it is in the cache (Euler, HeunSecond).
    void finish(int j, int lo, int hi) {
        const size_t k0 = at(0, j);
        FinishRow f = *out_.finish;
        f.h = out_.h + k0;
        f.hu = out_.hu + k0;
        f.hv = out_.hv + k0;
        f.rain_rate = f.rain_rate ? f.rain_rate + k0 : nullptr;
        f.lo = lo;
        f.hi = hi;
        int wlo, whi;
        out_.row_rain[j] = finish_row(f, wlo, whi);
        out_.wet_lo[j] = std::min(wlo, in_.nx);
        out_.wet_hi[j] = whi;
    }

    const StageIn& in_;
    const StageOut& out_;
    Scratch& s_;
};

// Not under ThreadSanitizer: the clones' ifunc resolvers run while the dynamic loader
// relocates, before the TSan runtime is up, and crash there (as spring_sum's would).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && !defined(__SANITIZE_THREAD__)
#define MR_CLONES [[gnu::flatten, gnu::target_clones("avx512f", "avx2", "default")]]
#else
#define MR_CLONES
#endif

MR_CLONES void finish_columns(double* MR_RESTRICT h, double* MR_RESTRICT hu, double* MR_RESTRICT hv, int lo, int hi, double c,
                              double dry) {
    if (c == 0.0) {  // no friction here (none, or Heun's stages applied it)
        for (int i = lo; i <= hi; ++i)
            if (!(h[i] > dry)) hu[i] = hv[i] = 0.0;
        return;
    }
    const double floor = std::max(dry, 1e-12);  // a depth the friction can divide by
    MR_IVDEP
    for (int i = lo; i <= hi; ++i) {
        const double hh = h[i], qx = hu[i], qy = hv[i];
        const double f = manning_divisor(hh, qx, qy, c, floor);
        hu[i] = hh > dry ? qx / f : 0.0;
        hv[i] = hh > dry ? qy / f : 0.0;
    }
}

MR_CLONES double wave_speed_columns(const double* MR_RESTRICT h, const double* MR_RESTRICT hu, const double* MR_RESTRICT hv, int lo,
                                   int hi, double g, double dry) {
    double s = 0.0, block[64];
    for (int i0 = lo; i0 <= hi; i0 += 64) {
        const int n = std::min(64, hi - i0 + 1);
        MR_IVDEP
        for (int t = 0; t < n; ++t) {  // vectorised; the maximum below is not (no fast-math)
            const double hh = h[i0 + t], hs = std::max(hh, dry);
            const double a = std::max(std::abs(hu[i0 + t] / hs), std::abs(hv[i0 + t] / hs)) + std::sqrt(g * hh);
            block[t] = hh > dry ? a : 0.0;
        }
        for (int t = 0; t < n; ++t) s = std::max(s, block[t]);
    }
    return s;
}

/// One chunk of rows, everything it calls inlined (flatten) and compiled three times: for
/// AVX-512 (8 doubles a vector, 32 registers: the face loops no longer spill; a third less
/// time than AVX2 on the EPYC here), for AVX2 (4 doubles) and for the baseline (SSE2),
/// picked at run time. No FMA in any (-ffp-contract=off): the results are the same on every
/// x86-64 (ShallowWater.StagesHaveTheSameBitsOnEveryInstructionSet).
MR_CLONES void sweep_chunk(const StageIn& in, const StageOut& out, StageKind kind, Scratch& scratch, int j0, int j1) {
    switch (kind) {
    case StageKind::Euler:
        if (in.second)
            Sweep<true, StageKind::Euler>(in, out, scratch).rows(j0, j1);
        else
            Sweep<false, StageKind::Euler>(in, out, scratch).rows(j0, j1);
        break;
    case StageKind::HeunFirst: Sweep<true, StageKind::HeunFirst>(in, out, scratch).rows(j0, j1); break;
    case StageKind::HeunSecond: Sweep<true, StageKind::HeunSecond>(in, out, scratch).rows(j0, j1); break;
    }
}

}  // namespace

void run_stage(const StageIn& in, const StageOut& out, StageKind kind) {
    // Chunks of rows large enough that the rows a chunk recomputes at its ends (a face row,
    // two rows of slopes) cost little, small enough to balance two to four threads.
    const int grain = std::max(8, in.ny / 32);
    tbb::parallel_for(
        tbb::blocked_range<int>(0, in.ny, grain),
        [&](const tbb::blocked_range<int>& rows) {
            thread_local Scratch scratch;
            scratch.resize(in.nx);
            sweep_chunk(in, out, kind, scratch, rows.begin(), rows.end());
        },
        tbb::simple_partitioner());
}

double cbrt_positive(double x) { return cbrt_estimate(x); }

double row_wave_speed(const double* h, const double* hu, const double* hv, int lo, int hi, double g, double dry) {
    return wave_speed_columns(h, hu, hv, lo, hi, g, dry);
}

double finish_row(const FinishRow& row, int& wet_lo, int& wet_hi) {
    double* h = row.h;
    double added = 0.0;
    if (row.rain_rate) {
        for (int i = row.lo; i <= row.hi; ++i) {
            const double r = row.rain_rate[i] * row.dt;
            h[i] += r;
            added += r;
        }
    } else if (row.rain != 0.0) {
        for (int i = row.lo; i <= row.hi; ++i) h[i] += row.rain;
    }
    finish_columns(h, row.hu, row.hv, row.lo, row.hi, row.c, row.dry);
    int lo = row.lo, hi = row.hi;
    while (lo <= hi && !(h[lo] > 0.0)) ++lo;
    while (hi >= lo && !(h[hi] > 0.0)) --hi;
    wet_lo = lo <= hi ? lo : INT_MAX;
    wet_hi = lo <= hi ? hi : -1;
    return added;
}

}  // namespace mr::swe
