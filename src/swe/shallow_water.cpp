// The shallow-water core (shallow_water.h): Audusse et al. 2004's hydrostatic reconstruction
// with HLL fluxes, first or second order, on the wet spans of each row.
#include "shallow_water.h"

#include "swe_flux.h"
#include "swe_stage.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace mr::swe {

namespace {

constexpr int kDilate = 2;  // columns beyond the wet ones a step may touch (two stages)
/// Metres an outfall's ghost bed lies below its edge cell's: deeper than any water.
constexpr double kOutfallDrop = 1e6;

template <class F>
void for_rows(int ny, F&& f) {
    tbb::parallel_for(tbb::blocked_range<int>(0, ny), [&](const tbb::blocked_range<int>& r) {
        for (int j = r.begin(); j != r.end(); ++j) f(j);
    });
}

double velocity(double h, double q, double dry) { return h > dry ? q / h : 0.0; }

}  // namespace

double ShallowWater::manning_c(double dt) const {
    return dt * def_.gravity * (def_.manning * def_.manning);  // Manning: q_new (1 + dt g n^2 |u_new| / h^(4/3)) = q
}

ShallowWater::ShallowWater(int nx, int ny, double dx, std::span<const double> bed, const ShallowWaterDef& def)
    : nx_(std::max(nx, 1)), ny_(std::max(ny, 1)), dx_(dx > 0.0 ? dx : 1.0), stride_(static_cast<size_t>(nx_) + 2), def_(def) {
    const size_t n = stride_ * (static_cast<size_t>(ny_) + 2);
    z_.assign(n, 0.0);
    h_.assign(n, 0.0);
    hu_.assign(n, 0.0);
    hv_.assign(n, 0.0);
    for (auto& t : t_) t.assign(n, 0.0);
    t_lo_.assign(ny_, 0);
    t_hi_.assign(ny_, -1);
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
    if (h_[k] > 0.0) mark_wet(i, j);
    balance_.exchanged += moved;
    return moved;
}

void ShallowWater::set_bed(int i, int j, double bed) {
    if (i < 0 || j < 0 || i >= nx_ || j >= ny_ || !std::isfinite(bed)) return;
    z_[at(i, j)] = bed;
}

double ShallowWater::volume() const {
    double v = 0.0;
    for (int j = 0; j < ny_; ++j) {
        double row = 0.0;
        for (int i = wet_lo_[j]; i <= wet_hi_[j]; ++i) row += h_[at(i, j)];  // 0 elsewhere
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
        for (int i = wet_lo_[j]; i <= wet_hi_[j]; ++i) {  // dry elsewhere
            const size_t k = at(i, j);
            if (h_[k] <= def_.dry_depth) continue;
            const double c = std::sqrt(def_.gravity * h_[k]);
            s = std::max({s, std::abs(hu_[k] / h_[k]) + c, std::abs(hv_[k] / h_[k]) + c});
        }
    return s;
}

void ShallowWater::fill_ghosts(std::vector<double>& h, std::vector<double>& hu, std::vector<double>& hv) {
    // One ghost per edge cell from its neighbour inside; `n` is the normal discharge's
    // array, `t` the transverse one, `sign` the inward direction.
    auto ghost = [&](size_t g, size_t in, const Edge& e, std::vector<double>& n, std::vector<double>& t, double sign) {
        z_[g] = z_[in];
        h[g] = h[in];
        n[g] = n[in];
        t[g] = t[in];
        switch (e.kind) {
        case EdgeKind::Wall: n[g] = -n[in]; break;
        case EdgeKind::Open: break;
        case EdgeKind::Outfall:
            // Dry and far below: the face's hydrostatic reconstruction cuts nothing from the
            // inside, and at second order the edge cell's slope towards it is the inner one
            // (minmod with a huge drop) or none (the surface rising to the edge).
            z_[g] = z_[in] - kOutfallDrop;
            h[g] = n[g] = t[g] = 0.0;
            break;
        case EdgeKind::Discharge:
            n[g] = h[in] > def_.dry_depth ? sign * e.value : 0.0;
            t[g] = 0.0;
            break;
        case EdgeKind::Depth: {
            const double hd = std::max(e.value, 0.0);
            n[g] = hd * velocity(h[in], n[in], def_.dry_depth);
            t[g] = hd * velocity(h[in], t[in], def_.dry_depth);
            h[g] = hd;
            break;
        }
        }
    };
    for (int j = 0; j < ny_; ++j) {
        ghost(at(-1, j), at(0, j), def_.west, hu, hv, 1.0);
        ghost(at(nx_, j), at(nx_ - 1, j), def_.east, hu, hv, -1.0);
    }
    for (int i = 0; i < nx_; ++i) {
        ghost(at(i, -1), at(i, 0), def_.south, hv, hu, 1.0);
        ghost(at(i, ny_), at(i, ny_ - 1), def_.north, hv, hu, -1.0);
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

double ShallowWater::stable_dt() {
    for_rows(ny_, [&](int j) {
        const size_t k0 = at(0, j);
        row_speed_[j] = row_wave_speed(h_.data() + k0, hu_.data() + k0, hv_.data() + k0, lo_[j], hi_[j], def_.gravity, def_.dry_depth);
    });
    const double s = *std::max_element(row_speed_.begin(), row_speed_.end());
    return s > 0.0 ? def_.cfl * dx_ / s : std::numeric_limits<double>::infinity();
}

void ShallowWater::stage(int kind, std::vector<double>* const* in, std::vector<double>* const* out, double dt, double w,
                         const FinishRow* finish) {
    fill_ghosts(*in[0], *in[1], *in[2]);
    StageIn si;
    si.nx = nx_;
    si.ny = ny_;
    si.stride = stride_;
    si.z = z_.data();
    si.h = in[0]->data();
    si.hu = in[1]->data();
    si.hv = in[2]->data();
    si.lo = lo_.data();
    si.hi = hi_.data();
    si.g = def_.gravity;
    si.dry = def_.dry_depth;
    si.r = dt / dx_;
    si.weight = dt * dx_;
    si.second = def_.second_order;
    si.friction = def_.second_order ? manning_c(dt) : 0.0;  // Heun: in each stage
    si.wall_west = def_.west.kind == EdgeKind::Wall;
    si.wall_east = def_.east.kind == EdgeKind::Wall;
    si.wall_south = def_.south.kind == EdgeKind::Wall;
    si.wall_north = def_.north.kind == EdgeKind::Wall;
    StageOut so;
    so.h = out[0]->data();
    so.hu = out[1]->data();
    so.hv = out[2]->data();
    so.dirty_lo = t_lo_.data();
    so.dirty_hi = t_hi_.data();
    so.row_out = row_out_.data();
    so.row_in = row_in_.data();
    so.row_clip = row_clip_.data();
    so.finish = finish;
    so.row_rain = row_rain_.data();
    so.wet_lo = wet_lo_.data();
    so.wet_hi = wet_hi_.data();
    run_stage(si, so, static_cast<StageKind>(kind));
    double sum_out = 0.0, sum_in = 0.0;
    for (int j = 0; j < ny_; ++j) {  // row order: the same on any number of threads
        sum_out += row_out_[j];
        sum_in += row_in_[j];
    }
    balance_.outflow += w * sum_out;
    balance_.inflow += w * sum_in;
}

FinishRow ShallowWater::finish_template(double dt) const {
    FinishRow row;
    const bool masked = !rain_mask_.empty();
    row.rain_rate = masked ? rain_mask_.data() : nullptr;
    row.rain = rain_ > 0.0 && !masked ? rain_ * dt : 0.0;
    row.dt = dt;
    row.c = def_.second_order ? 0.0 : manning_c(dt);  // Heun's stages apply it themselves
    row.dry = def_.dry_depth;
    return row;
}

void ShallowWater::finish_step(double dt) {
    const FinishRow base = finish_template(dt);
    for_rows(ny_, [&](int j) {
        const size_t k0 = at(0, j);
        FinishRow row = base;
        row.h = h_.data() + k0;
        row.hu = hu_.data() + k0;
        row.hv = hv_.data() + k0;
        row.rain_rate = base.rain_rate ? base.rain_rate + k0 : nullptr;
        row.lo = lo_[j];
        row.hi = hi_[j];
        int wlo, whi;
        row_rain_[j] = finish_row(row, wlo, whi);
        wet_lo_[j] = std::min(wlo, nx_);
        wet_hi_[j] = whi;
    });
    finish_tail(dt);
}

void ShallowWater::finish_tail(double dt) {
    if (!rain_mask_.empty()) {
        double sum = 0.0;
        for (int j = 0; j < ny_; ++j) sum += row_rain_[j];  // row order: any thread count
        balance_.rain += sum * dx_ * dx_;
    } else {
        balance_.rain += finish_template(dt).rain * dx_ * dx_ * static_cast<double>(nx_) * ny_;
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
    }
}

double ShallowWater::step(double max_dt) {
    update_spans();
    const double dt = std::min(stable_dt(), max_dt);
    if (!(dt > 0.0) || !std::isfinite(dt)) return 0.0;
    uint64_t cells = 0;
    for (int j = 0; j < ny_; ++j) cells += static_cast<uint64_t>(std::max(hi_[j] - lo_[j] + 1, 0));
    std::vector<double>* const state[3] = {&h_, &hu_, &hv_};
    std::vector<double>* const scratch[3] = {&t_[0], &t_[1], &t_[2]};
    if (!def_.second_order) {
        const FinishRow finish = finish_template(dt);  // rain and friction on each row as it is written
        stage(static_cast<int>(StageKind::Euler), state, scratch, dt, 1.0, &finish);
        // The new state is the scratch: inside each row's span the stage wrote it, outside
        // it both buffers hold zeros (the span covers every wet cell and its neighbours, and
        // the stage cleared what the scratch held there), so swapping replaces a copy of
        // the span. The old state, now the scratch, is non-zero only inside the spans the
        // stage just marked dirty.
        h_.swap(t_[0]);
        hu_.swap(t_[1]);
        hv_.swap(t_[2]);
        finish_tail(dt);
    } else {
        // Heun (SSP-RK2): U1 = U + dt L(U), U2 = U1 + dt L(U1), U = (U + U2) / 2.
        stage(static_cast<int>(StageKind::HeunFirst), state, scratch, dt, 0.5);
        const FinishRow finish = finish_template(dt);  // done on each row as it is written
        stage(static_cast<int>(StageKind::HeunSecond), scratch, state, dt, 0.5, &finish);
        cells *= 2;
        finish_tail(dt);
    }
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
