// The shallow-water core (shallow_water.h): Audusse et al. 2004's hydrostatic reconstruction
// with HLL fluxes, first or second order, on the wet spans of each row.
#include "shallow_water.h"

#include "swe_flux.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr::swe {

namespace {

constexpr int kDilate = 2;  // columns beyond the wet ones a step may touch (two stages)

template <class F>
void for_rows(int ny, F&& f) {
    tbb::parallel_for(tbb::blocked_range<int>(0, ny), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j != r.end(); ++j) f(j);
    });
}

double velocity(double h, double q, double dry) { return h > dry ? q / h : 0.0; }

}  // namespace

ShallowWater::ShallowWater(int nx, int ny, double dx, std::span<const double> bed, const ShallowWaterDef& def)
    : nx_(std::max(nx, 1)), ny_(std::max(ny, 1)), dx_(dx > 0.0 ? dx : 1.0), stride_(static_cast<size_t>(nx_) + 2), def_(def) {
    const size_t n = stride_ * (static_cast<size_t>(ny_) + 2);
    z_.assign(n, 0.0);
    h_.assign(n, 0.0);
    hu_.assign(n, 0.0);
    hv_.assign(n, 0.0);
    u_.assign(n, 0.0);
    v_.assign(n, 0.0);
    for (auto& s : sx_) s.assign(n, 0.0);
    for (auto& s : sy_) s.assign(n, 0.0);
    fx_.assign((static_cast<size_t>(nx_) + 1) * ny_ * 4, 0.0);
    fy_.assign(static_cast<size_t>(nx_) * (ny_ + 1) * 4, 0.0);
    lo_.assign(ny_, 0);
    hi_.assign(ny_, -1);
    wet_lo_.assign(ny_, nx_);
    wet_hi_.assign(ny_, -1);
    row_out_.assign(ny_ + 1, 0.0);
    row_in_.assign(ny_ + 1, 0.0);
    row_speed_.assign(ny_, 0.0);
    row_rain_.assign(ny_, 0.0);
    row_clip_.assign(ny_, 0);
    for (int j = 0; j < ny_; ++j)
        for (int i = 0; i < nx_; ++i) {
            const size_t k = static_cast<size_t>(j) * nx_ + i;
            z_[at(i, j)] = k < bed.size() && std::isfinite(bed[k]) ? bed[k] : 0.0;
        }
    balance_reset();
}

void ShallowWater::set_state(int i, int j, double depth, double qx, double qy) {
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return;
    const size_t k = at(i, j);
    h_[k] = std::isfinite(depth) ? std::max(depth, 0.0) : 0.0;
    hu_[k] = h_[k] > 0.0 && std::isfinite(qx) ? qx : 0.0;
    hv_[k] = h_[k] > 0.0 && std::isfinite(qy) ? qy : 0.0;
    refresh(k);
    if (h_[k] > 0.0) mark_wet(i, j);
}

void ShallowWater::mark_wet(int i, int j) {
    wet_lo_[j] = std::min(wet_lo_[j], i);
    wet_hi_[j] = std::max(wet_hi_[j], i);
}

void ShallowWater::set_rain_mask(std::vector<double> rate) {
    rain_mask_.clear();
    rain_lo_.assign(ny_, nx_);
    rain_hi_.assign(ny_, -1);
    if (rate.empty()) return;
    rain_mask_.assign(h_.size(), 0.0);
    for (int j = 0; j < ny_; ++j)
        for (int i = 0; i < nx_; ++i) {
            const size_t k = static_cast<size_t>(j) * nx_ + i;
            const double r = k < rate.size() && std::isfinite(rate[k]) ? std::max(rate[k], 0.0) : 0.0;
            rain_mask_[at(i, j)] = r;
            if (r > 0.0) {
                rain_lo_[j] = std::min(rain_lo_[j], i);
                rain_hi_[j] = std::max(rain_hi_[j], i);
            }
        }
}

double ShallowWater::exchange(int i, int j, double volume, double momentum_x, double momentum_y) {
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_ || !std::isfinite(volume) || volume == 0.0) return 0.0;
    if (!std::isfinite(momentum_x) || !std::isfinite(momentum_y)) momentum_x = momentum_y = 0.0;
    const size_t k = at(i, j);
    const double area = dx_ * dx_, h0 = h_[k];
    double moved = volume;
    if (volume > 0.0) {
        h_[k] = h0 + volume / area;
    } else {
        const double take = std::min(-volume, h0 * area);
        h_[k] = take >= h0 * area ? 0.0 : std::max(h0 - take / area, 0.0);
        moved = (h_[k] - h0) * area;
    }
    const double share = moved / volume;  // 1 unless the cell held less than asked
    hu_[k] += share * momentum_x / area;
    hv_[k] += share * momentum_y / area;
    if (h_[k] <= def_.dry_depth) hu_[k] = hv_[k] = 0.0;
    refresh(k);
    if (h_[k] > 0.0) mark_wet(i, j);
    balance_.exchanged += moved;
    return moved;
}

void ShallowWater::refresh(size_t k) {
    u_[k] = velocity(h_[k], hu_[k], def_.dry_depth);
    v_[k] = velocity(h_[k], hv_[k], def_.dry_depth);
}

void ShallowWater::set_bed(int i, int j, double bed) {
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_ || !std::isfinite(bed)) return;
    z_[at(i, j)] = bed;
}

double ShallowWater::volume() const {
    double v = 0.0;
    for (int j = 0; j < ny_; ++j) {
        double row = 0.0;
        for (int i = 0; i < nx_; ++i) row += h_[at(i, j)];
        v += row;
    }
    return v * dx_ * dx_;
}

void ShallowWater::balance_reset() {
    balance_ = {};
    balance_.initial = volume();
}

MassBalance ShallowWater::balance() const {
    MassBalance b = balance_;
    b.stored = volume();
    return b;
}

double ShallowWater::max_wave_speed() const {
    double s = 0.0;
    for (int j = 0; j < ny_; ++j)
        for (int i = 0; i < nx_; ++i) {
            const size_t k = at(i, j);
            if (h_[k] <= def_.dry_depth) continue;
            const double c = std::sqrt(def_.gravity * h_[k]);
            s = std::max({s, std::abs(hu_[k] / h_[k]) + c, std::abs(hv_[k] / h_[k]) + c});
        }
    return s;
}

void ShallowWater::fill_ghosts() {
    // One ghost per edge cell from its neighbour inside; `n` is the normal discharge's
    // array, `t` the transverse one, `sign` the inward direction.
    auto ghost = [&](size_t g, size_t in, const Edge& e, std::vector<double>& n, std::vector<double>& t, double sign) {
        z_[g] = z_[in];
        h_[g] = h_[in];
        n[g] = n[in];
        t[g] = t[in];
        switch (e.kind) {
        case EdgeKind::Wall: n[g] = -n[in]; break;
        case EdgeKind::Open: break;
        case EdgeKind::Discharge:
            n[g] = h_[in] > def_.dry_depth ? sign * e.value : 0.0;
            t[g] = 0.0;
            break;
        case EdgeKind::Depth: {
            const double hd = std::max(e.value, 0.0);
            n[g] = hd * velocity(h_[in], n[in], def_.dry_depth);
            t[g] = hd * velocity(h_[in], t[in], def_.dry_depth);
            h_[g] = hd;
            break;
        }
        }
        refresh(g);
    };
    for (int j = 0; j < ny_; ++j) {
        ghost(at(-1, j), at(0, j), def_.west, hu_, hv_, 1.0);
        ghost(at(nx_, j), at(nx_ - 1, j), def_.east, hu_, hv_, -1.0);
    }
    for (int i = 0; i < nx_; ++i) {
        ghost(at(i, -1), at(i, 0), def_.south, hv_, hu_, 1.0);
        ghost(at(i, ny_), at(i, ny_ - 1), def_.north, hv_, hu_, -1.0);
    }
}

void ShallowWater::update_spans() {
    const bool masked = !rain_mask_.empty();
    const bool everywhere = (rain_ > 0.0 && !masked) || def_.west.kind >= EdgeKind::Discharge || def_.east.kind >= EdgeKind::Discharge ||
                            def_.south.kind >= EdgeKind::Discharge || def_.north.kind >= EdgeKind::Discharge;
    for (int j = 0; j < ny_; ++j) {
        if (everywhere) {
            lo_[j] = 0;
            hi_[j] = nx_ - 1;
            continue;
        }
        int lo = nx_, hi = -1;
        for (int r = std::max(j - 1, 0); r <= std::min(j + 1, ny_ - 1); ++r) {
            lo = std::min(lo, wet_lo_[r]);
            hi = std::max(hi, wet_hi_[r]);
        }
        if (hi >= lo) {
            lo = std::max(lo - kDilate, 0);
            hi = std::min(hi + kDilate, nx_ - 1);
        }
        if (masked && rain_hi_[j] >= rain_lo_[j]) {  // raining cells take their rain in finish_step
            lo = std::min(lo, rain_lo_[j]);
            hi = std::max(hi, rain_hi_[j]);
        }
        lo_[j] = hi < lo ? 0 : lo;
        hi_[j] = hi;
    }
}

void ShallowWater::compute_slopes() {
    // Limited slopes of h, eta = h + z, u and v along x (neighbours k -/+ 1) and y (k -/+ stride).
    const size_t sn = stride_;
    const double *h = h_.data(), *z = z_.data(), *u = u_.data(), *v = v_.data();
    auto slope = [](double l, double c, double r) { return minmod(c - l, r - c); };
    for_rows(ny_, [&](int j) {
        if (hi_[j] < lo_[j]) return;
        const int i1 = std::min(hi_[j] + 1, nx_ - 1);
        for (int i = std::max(lo_[j] - 1, 0); i <= i1; ++i) {
            const size_t k = at(i, j);
            for (int axis = 0; axis < 2; ++axis) {
                const size_t d = axis ? sn : 1;
                std::vector<double>* out = axis ? sy_ : sx_;
                out[0][k] = slope(h[k - d], h[k], h[k + d]);
                out[1][k] = slope(h[k - d] + z[k - d], h[k] + z[k], h[k + d] + z[k + d]);
                out[2][k] = slope(u[k - d], u[k], u[k + d]);
                out[3][k] = slope(v[k - d], v[k], v[k + d]);
            }
        }
    });
}

double ShallowWater::stable_dt() {
    for_rows(ny_, [&](int j) {
        double s = 0.0;
        for (int i = lo_[j]; i <= hi_[j]; ++i) {
            const size_t k = at(i, j);
            if (h_[k] <= def_.dry_depth) continue;
            const double c = std::sqrt(def_.gravity * h_[k]);
            s = std::max({s, std::abs(hu_[k] / h_[k]) + c, std::abs(hv_[k] / h_[k]) + c});
        }
        row_speed_[j] = s;
    });
    const double s = *std::max_element(row_speed_.begin(), row_speed_.end());
    return s > 0.0 ? def_.cfl * dx_ / s : std::numeric_limits<double>::infinity();
}

namespace {

/// Cell k's reconstructed state on its side `side` (+1: towards +x or +y) along the axis
/// whose slopes are `s` (h, eta, u, v) and whose normal velocity is u (x) or v (y).
FaceState face_state(const std::vector<double>& z, const std::vector<double>& h, const std::vector<double>& uc,
                     const std::vector<double>& vc, const std::vector<double> (&s)[4], size_t k, double side, bool y_axis) {
    const double hf = h[k] + 0.5 * side * s[0][k];
    const double etaf = h[k] + z[k] + 0.5 * side * s[1][k];
    const double u = uc[k] + 0.5 * side * s[2][k];
    const double v = vc[k] + 0.5 * side * s[3][k];
    return y_axis ? FaceState{hf, v, u, etaf - hf} : FaceState{hf, u, v, etaf - hf};
}

void put(std::vector<double>& faces, size_t f, const FaceFlux& flux) {
    faces[4 * f + 0] = flux.mass;
    faces[4 * f + 1] = flux.mom_minus;
    faces[4 * f + 2] = flux.mom_plus;
    faces[4 * f + 3] = flux.trans;
}

}  // namespace

void ShallowWater::flux_rows(double weight) {
    const double g = def_.gravity;
    const size_t nfx = static_cast<size_t>(nx_) + 1;
    auto y_faces = [&](int j, int lo, int hi, int both_lo, int both_hi) {
        // Face row j (between rows j-1 and j) over [lo, hi]; only [both_lo, both_hi] can
        // hold water on either side, the rest is dry on both and carries nothing.
        for (int i = lo; i <= hi; ++i) {
            const size_t f = static_cast<size_t>(j) * nx_ + i;
            if (i < both_lo || i > both_hi) {
                put(fy_, f, {});
                continue;
            }
            const FaceState a = face_state(z_, h_, u_, v_, sy_, at(i, j - 1), 1.0, true);
            const FaceState b = face_state(z_, h_, u_, v_, sy_, at(i, j), -1.0, true);
            put(fy_, f, hydrostatic_flux(a, b, g));
        }
    };
    for_rows(ny_, [&](int j) {
        row_out_[j] = row_in_[j] = 0.0;
        if (hi_[j] >= lo_[j]) {
            for (int i = lo_[j]; i <= hi_[j] + 1; ++i) {
                const FaceState a = face_state(z_, h_, u_, v_, sx_, at(i - 1, j), 1.0, false);
                const FaceState b = face_state(z_, h_, u_, v_, sx_, at(i, j), -1.0, false);
                put(fx_, static_cast<size_t>(j) * nfx + i, hydrostatic_flux(a, b, g));
            }
        }
        // Face row j: the union of rows j-1 and j's spans, computed where both hold them.
        const int plo = j > 0 ? lo_[j - 1] : lo_[j], phi = j > 0 ? hi_[j - 1] : hi_[j];
        const bool pe = phi < plo, ce = hi_[j] < lo_[j];
        if (!pe || !ce) {
            const int ulo = pe ? lo_[j] : ce ? plo : std::min(plo, lo_[j]);
            const int uhi = pe ? hi_[j] : ce ? phi : std::max(phi, hi_[j]);
            y_faces(j, ulo, uhi, std::max(plo, lo_[j]), std::min(phi, hi_[j]));
        }
        if (j == ny_ - 1 && !ce) y_faces(ny_, lo_[j], hi_[j], lo_[j], hi_[j]);
        // The edges' mass, outward positive.
        double out = 0.0, in = 0.0;
        auto tally = [&](double outward) { (outward > 0.0 ? out : in) += std::abs(outward); };
        if (!ce && lo_[j] == 0) tally(-fx_[4 * (static_cast<size_t>(j) * nfx)]);
        if (!ce && hi_[j] == nx_ - 1) tally(fx_[4 * (static_cast<size_t>(j) * nfx + nx_)]);
        if (j == 0 && !ce)
            for (int i = lo_[j]; i <= hi_[j]; ++i) tally(-fy_[4 * static_cast<size_t>(i)]);
        if (j == ny_ - 1 && !ce)
            for (int i = lo_[j]; i <= hi_[j]; ++i) tally(fy_[4 * (static_cast<size_t>(ny_) * nx_ + i)]);
        row_out_[j] = out * weight;
        row_in_[j] = in * weight;
    });
}

void ShallowWater::euler_stage(double dt, std::vector<double>& h, std::vector<double>& hu, std::vector<double>& hv) {
    fill_ghosts();
    if (def_.second_order) compute_slopes();
    flux_rows(dt * dx_);
    double out = 0.0, in = 0.0;
    for (int j = 0; j < ny_; ++j) {
        out += row_out_[j];
        in += row_in_[j];
    }
    const double w = def_.second_order ? 0.5 : 1.0;  // Heun averages the two stages
    balance_.outflow += w * out;
    balance_.inflow += w * in;
    const double r = dt / dx_, g = def_.gravity;
    const size_t nfx = static_cast<size_t>(nx_) + 1;
    for_rows(ny_, [&](int j) {
        uint64_t clip = 0;
        for (int i = lo_[j]; i <= hi_[j]; ++i) {
            const size_t k = at(i, j);
            const double* w0 = &fx_[4 * (static_cast<size_t>(j) * nfx + i)];
            const double* e0 = w0 + 4;
            const double* s0 = &fy_[4 * (static_cast<size_t>(j) * nx_ + i)];
            const double* n0 = &fy_[4 * (static_cast<size_t>(j + 1) * nx_ + i)];
            // Audusse's centred bed-slope term of the second order (0 at first order).
            const double scx = -g * h_[k] * (sx_[1][k] - sx_[0][k]);
            const double scy = -g * h_[k] * (sy_[1][k] - sy_[0][k]);
            double hn = h_[k] - r * (e0[0] - w0[0] + n0[0] - s0[0]);
            const double qx = hu_[k] - r * (e0[1] - w0[2] + n0[3] - s0[3]) + r * scx;
            const double qy = hv_[k] - r * (n0[1] - s0[2] + e0[3] - w0[3]) + r * scy;
            if (hn < 0.0) {
                hn = 0.0;
                ++clip;
            }
            h[k] = hn;
            hu[k] = qx;
            hv[k] = qy;  // velocities refreshed by the caller's next pass (Heun's or finish_step)
        }
        row_clip_[j] += clip;
    });
}

void ShallowWater::finish_step(double dt) {
    const double g = def_.gravity, n2 = def_.manning * def_.manning, dry = def_.dry_depth;
    const bool masked = !rain_mask_.empty();
    const double rain = rain_ > 0.0 && !masked ? rain_ * dt : 0.0;
    for_rows(ny_, [&](int j) {
        int wlo = nx_, whi = -1;
        double row_rain = 0.0;
        for (int i = lo_[j]; i <= hi_[j]; ++i) {
            const size_t k = at(i, j);
            if (masked) {
                const double r = rain_mask_[k] * dt;
                h_[k] += r;
                row_rain += r;
            } else {
                h_[k] += rain;
            }
            if (h_[k] <= dry) {
                hu_[k] = hv_[k] = 0.0;
            } else if (n2 > 0.0) {
                // Semi-implicit Manning: q / (1 + dt g n^2 |u| / h^(4/3)).
                const double speed = std::hypot(hu_[k], hv_[k]) / h_[k];
                const double f = 1.0 + dt * g * n2 * speed / (h_[k] * std::cbrt(h_[k]));
                hu_[k] /= f;
                hv_[k] /= f;
            }
            refresh(k);
            if (h_[k] > 0.0) {
                wlo = std::min(wlo, i);
                whi = std::max(whi, i);
            }
        }
        wet_lo_[j] = wlo;
        wet_hi_[j] = whi;
        row_rain_[j] = row_rain;
    });
    if (masked) {
        double sum = 0.0;
        for (int j = 0; j < ny_; ++j) sum += row_rain_[j];  // row order: any thread count
        balance_.rain += sum * dx_ * dx_;
    } else {
        balance_.rain += rain * dx_ * dx_ * static_cast<double>(nx_) * ny_;
    }
    apply_sources(dt);
    for (int j = 0; j < ny_; ++j) {
        stats_.clipped += row_clip_[j];
        row_clip_[j] = 0;
    }
}

void ShallowWater::apply_sources(double dt) {
    const double area = dx_ * dx_;
    for (const PointSource& s : sources_) {
        if (s.i < 0 || s.j < 0 || s.i >= nx_ || s.j >= ny_ || !std::isfinite(s.discharge) || s.discharge == 0.0) continue;
        const size_t k = at(s.i, s.j);
        if (s.discharge > 0.0) {
            h_[k] += s.discharge * dt / area;
            balance_.inflow += s.discharge * dt;
            mark_wet(s.i, s.j);
        } else if (h_[k] > 0.0) {
            // A sink: at most what the cell holds; the velocity kept (discharges scaled).
            const double h0 = h_[k], take = -s.discharge * dt;
            h_[k] = take >= h0 * area ? 0.0 : std::max(h0 - take / area, 0.0);
            balance_.sunk += (h0 - h_[k]) * area;
            const double keep = h_[k] > def_.dry_depth ? h_[k] / h0 : 0.0;
            hu_[k] *= keep;
            hv_[k] *= keep;
        }
        refresh(k);
    }
}

double ShallowWater::step(double max_dt) {
    update_spans();
    const double dt = std::min(stable_dt(), max_dt);
    if (!(dt > 0.0) || !std::isfinite(dt)) return 0.0;
    uint64_t cells = 0;
    for (int j = 0; j < ny_; ++j) cells += static_cast<uint64_t>(std::max(hi_[j] - lo_[j] + 1, 0));
    if (!def_.second_order) {
        euler_stage(dt, h_, hu_, hv_);
    } else {
        // Heun (SSP-RK2): U1 = U + dt L(U), U2 = U1 + dt L(U1), U = (U + U2) / 2.
        h0_.resize(h_.size());
        hu0_.resize(h_.size());
        hv0_.resize(h_.size());
        for_rows(ny_, [&](int j) {
            for (int i = lo_[j]; i <= hi_[j]; ++i) {
                const size_t k = at(i, j);
                h0_[k] = h_[k];
                hu0_[k] = hu_[k];
                hv0_[k] = hv_[k];
            }
        });
        euler_stage(dt, h_, hu_, hv_);
        for_rows(ny_, [&](int j) {
            for (int i = lo_[j]; i <= hi_[j]; ++i) {
                const size_t k = at(i, j);
                if (h_[k] <= def_.dry_depth) hu_[k] = hv_[k] = 0.0;
                refresh(k);
            }
        });
        euler_stage(dt, h_, hu_, hv_);
        for_rows(ny_, [&](int j) {
            for (int i = lo_[j]; i <= hi_[j]; ++i) {
                const size_t k = at(i, j);
                h_[k] = 0.5 * (h0_[k] + h_[k]);
                hu_[k] = 0.5 * (hu0_[k] + hu_[k]);
                hv_[k] = 0.5 * (hv0_[k] + hv_[k]);  // finish_step refreshes the velocities
            }
        });
        cells *= 2;
    }
    finish_step(dt);
    time_ += dt;
    ++stats_.substeps;
    stats_.cell_updates += cells;
    return dt;
}

void ShallowWater::advance(double duration) {
    double left = duration;
    while (left > 1e-12 * std::max(duration, 1.0)) {
        double dt = step(left);
        if (dt <= 0.0) {
            // Nothing flows: the sources and rain alone.
            update_spans();
            finish_step(left);
            time_ += left;
            dt = left;
        }
        left -= dt;
    }
}

}  // namespace mr::swe
