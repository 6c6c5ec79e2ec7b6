// metariver surface: feature-weighted Laplacian / Taubin smoothing of the extracted mesh.
//
// Loeschner, Boettcher, Jeske, Bender, "Weighted Laplacian smoothing for surface
// reconstruction of particle-based fluids" (VMV 2023; splashsurf): Laplacian steps, each
// vertex weighted by how much fluid lies around it so that splashes keep their shape.
// Taubin, "A signal processing approach to fair surface design" (SIGGRAPH 1995):
// alternating steps lambda > 0 and mu < -lambda cut high frequencies and pass low ones.
// Taubin, Zhang, Golub, "Optimal surface smoothing as filter design" (ECCV 1996): N steps
// of sizes 1 / r_i, r_i the roots of the Chebyshev polynomial of degree N on a band
// [a, 2], make the filter that damps that band most evenly; N = 8 on [0.1, 2] damps it
// to 0.05 or less, where 16 uniform steps of 1 leave its low end at 0.19.
//
//   hidden   (parallel, with a ground) A vertex below the ground (the terrain's mesh: the
//            river's bed, about half of its vertices) keeps its place and reads nothing.
//   weights  (parallel; eight vertices at a time with AVX2, smoothing_simd.h, the same
//            floats as the scalar loop) The field sampled (trilinear) one lone ball's iso
//            distance inside the surface, along the normal marching cubes gave the vertex
//            (the field's gradient): about the fluid behind it, in units of the kernel's
//            centre value. A lone particle reads 1 (its centre), two touching ones about
//            1.4, still water 2 to 4: w = smoothstep((v - N / 2) / (N / 2)), N =
//            feature_count, 0 below kMinWeight. Where the blocks' maxima say the value
//            cannot exceed N / 2, the scalar loop reads no sample. Only
//            the vertices with w > 0 ("moving") cost anything from here on: a frame of
//            spray and drops costs little more than this pass.
//   fans     (parallel) One pass over the triangles lists those with a moving corner (the
//            only ones whose shape changes) and counts their corners; a second over the
//            listed ones files, under each moving corner, the triangle's next and previous
//            vertex (a counting sort by moving vertex): on a closed oriented manifold a
//            vertex's "next" vertices are its neighbours, each once, and the (next,
//            previous) pairs are its fan. A moving vertex whose fan does not close (its
//            nexts are not its previouses) lies on an open boundary and is pinned.
//   steps    (parallel, double-buffered gathers over compact copies of the moving
//            vertices, padded to 16 bytes for one SSE load each) p' = p + w s (mean of
//            neighbours - p), s from smoothing_step_sizes(); the neighbours that do not
//            move are summed once, before the first step.
//   normals  (parallel gathers) Area-weighted from the smoothed fans for the moving
//            vertices; every other vertex keeps the field's gradient normal (a neighbour of
//            a moving vertex too: near the edge of the moving region its neighbours moved
//            little). Optional passes average each moving vertex's normal with its
//            neighbours'.
//   volume   Laplacian with keep_volume: the steps changed the enclosed volume by about
//            sum over the moving vertices of (their move) . (their fan's area normal) / 6
//            (first order: the volume's gradient at a vertex), and every moving vertex
//            moves along its normal by w d, d = -(that change) / sum w A_v, A_v a third
//            of its fan's area: the first-order volume change of that offset.
// Every sum runs in a fixed order (triangle order, fixed chunks of vertices), so the
// result does not depend on the thread count.
#include <metariver/surface.h>

#include "field_probe.h"
#include "smoothing_shares.h"
#include "smoothing_simd.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace mr {

namespace {

using P4 = SmoothingWorkspace::P4;
using smoothing_shares::for_split;
using smoothing_shares::ms_since;
using smoothing_shares::kMinSplit;
using smoothing_shares::Shares;

/// Chebyshev steps come in cycles of at most this many: longer cycles amplify the
/// middle of the band in between (50x at 20 steps on [0.1, 2]) and with it float error.
constexpr int kChebyshevCycle = 8;
/// Feature weights below this are 0: the vertex does not move (a step of a few per cent
/// of the way is not worth its cost; mostly lone drops and pairs).
constexpr float kMinWeight = 0.05f;
/// SmoothingWorkspace::moving_index of a vertex that does not move.
constexpr uint32_t kFixed = 0xffffffffu;

float smoothstep01(float x) {
    x = std::clamp(x, 0.0f, 1.0f);
    return x * x * (3.0f - 2.0f * x);
}

/// Lists the triangles with a moving corner (ws.listed, by share; their number in
/// ws.stats.triangles) and builds the fans of the moving vertices (ring_start per moving
/// index, next, prev, next_m). False when an index is out of range.
/// A counting sort by moving vertex in two parallel passes over shares of the triangles:
/// each share counts its listed triangles and its corners per moving vertex, and then
/// fills from offsets that put share 0's corners before share 1's, so every fan and the
/// list come out in triangle order whatever the number of shares.
bool build_fans(const SurfaceMesh& m, SmoothingWorkspace& ws) {
    const size_t nv = m.positions.size(), nm = ws.moving.size();
    const uint32_t* idx = m.indices.data();
    const size_t nt = m.indices.size() / 3;
    const uint32_t* mi = ws.moving_index.data();
    const Shares sh(nt, 2 * kMinSplit);
    const size_t shares = sh.count;
    // counts[c * nm + k]: share c's corners of moving vertex k, then its cursor. Share c's
    // listed triangles go to ws.listed from lo on, share_listed[c] of them (the fill pass
    // visits only them: in a river's frame about a third of the triangles).
    ws.fan_counts.assign(shares * nm, 0u);
    ws.listed.resize(nt);
    uint32_t* listed_at = ws.listed.data();
    uint32_t share_listed[Shares::kMax] = {};
    std::atomic<bool> bad{false};
    sh.run([&](size_t c, size_t lo, size_t hi) {
        uint32_t* cnt = ws.fan_counts.data() + c * nm;
        uint32_t* out = listed_at + lo;
        uint32_t n = 0;
        for (size_t t = lo; t < hi; ++t) {
            const uint32_t a = idx[3 * t], b = idx[3 * t + 1], cc = idx[3 * t + 2];
            if (a >= nv || b >= nv || cc >= nv) {
                bad.store(true, std::memory_order_relaxed);
                return;
            }
            const uint32_t ma = mi[a], mb = mi[b], mc = mi[cc];
            if ((ma & mb & mc) == kFixed) continue;  // no moving corner
            out[n++] = static_cast<uint32_t>(t);
            if (ma != kFixed) ++cnt[ma];
            if (mb != kFixed) ++cnt[mb];
            if (mc != kFixed) ++cnt[mc];
        }
        share_listed[c] = n;
    });
    if (bad.load()) return false;
    ws.stats.triangles = 0;
    for (size_t c = 0; c < shares; ++c) ws.stats.triangles += share_listed[c];
    // Offsets: vertex by vertex, share by share (each count becomes its share's cursor).
    ws.ring_start.resize(nm + 1);
    uint32_t* start = ws.ring_start.data();
    uint32_t at = 0;
    for (size_t k = 0; k < nm; ++k) {
        start[k] = at;
        for (size_t c = 0; c < shares; ++c) {
            uint32_t& x = ws.fan_counts[c * nm + k];
            const uint32_t n = x;
            x = at;
            at += n;
        }
    }
    start[nm] = at;
    ws.next.resize(at);
    ws.prev.resize(at);
    ws.next_m.resize(at);
    uint32_t* next = ws.next.data();
    uint32_t* prev = ws.prev.data();
    uint32_t* next_m = ws.next_m.data();
    sh.run([&](size_t c, size_t lo, size_t) {
        uint32_t* cur = ws.fan_counts.data() + c * nm;
        for (const uint32_t* it = listed_at + lo; it != listed_at + lo + share_listed[c]; ++it) {
            const uint32_t t = *it;
            const uint32_t a = idx[3 * size_t(t)], b = idx[3 * size_t(t) + 1], cc = idx[3 * size_t(t) + 2];
            const uint32_t ma = mi[a], mb = mi[b], mc = mi[cc];
            if (ma != kFixed) {
                const uint32_t x = cur[ma]++;
                next[x] = b, prev[x] = cc, next_m[x] = mb;
            }
            if (mb != kFixed) {
                const uint32_t x = cur[mb]++;
                next[x] = cc, prev[x] = a, next_m[x] = mc;
            }
            if (mc != kFixed) {
                const uint32_t x = cur[mc]++;
                next[x] = a, prev[x] = b, next_m[x] = ma;
            }
        }
    });
    return true;
}

/// Whether moving vertex k's fan closes: its nexts are its previouses. An open fan is a
/// chain whose last next and first previous differ, so the sums (and xors) of the nexts
/// and of the previouses differ; O(degree), unlike matching the pairs.
bool fan_closed(const SmoothingWorkspace& ws, size_t k) {
    const uint32_t b = ws.ring_start[k], e = ws.ring_start[k + 1];
    if (b == e) return false;
    uint64_t sn = 0, sp = 0;
    uint32_t xn = 0, xp = 0;
    for (uint32_t x = b; x < e; ++x) {
        sn += ws.next[x], sp += ws.prev[x];
        xn ^= ws.next[x], xp ^= ws.prev[x];
    }
    return sn == sp && xn == xp;
}

/// One step over the moving vertices (compact: index k): dst = src + s (w / degree *
/// (sum of the fixed neighbours + sum of the moving ones) - w src).
void laplacian_step(const SmoothingWorkspace& ws, const P4* src, P4* dst, float s) {
    const uint32_t* start = ws.ring_start.data();
    const uint32_t* inner = ws.inner.data();
    const uint32_t* nbr = ws.nbr.data();
    const P4* fixed = ws.fixed_sum.data();
    const float* wd = ws.step_weight.data();
    const float* w = ws.moving_weight.data();
    for_split(ws.moving.size(), [&](size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) {
            const uint32_t b = start[k], e = b + inner[k];
#if defined(__SSE2__)
            // Two running sums (even and odd neighbours), so the adds do not wait on each
            // other.
            __m128 s0 = _mm_load_ps(&fixed[k].x), s1 = _mm_setzero_ps();
            uint32_t x = b;
            for (; x + 1 < e; x += 2) {
                s0 = _mm_add_ps(s0, _mm_load_ps(&src[nbr[x]].x));
                s1 = _mm_add_ps(s1, _mm_load_ps(&src[nbr[x + 1]].x));
            }
            if (x < e) s0 = _mm_add_ps(s0, _mm_load_ps(&src[nbr[x]].x));
            const __m128 sum = _mm_add_ps(s0, s1);
            const __m128 p = _mm_load_ps(&src[k].x);
            const __m128 d = _mm_sub_ps(_mm_mul_ps(_mm_set1_ps(wd[k]), sum), _mm_mul_ps(_mm_set1_ps(w[k]), p));
            _mm_store_ps(&dst[k].x, _mm_add_ps(p, _mm_mul_ps(_mm_set1_ps(s), d)));
#else
            float s0[3] = {fixed[k].x, fixed[k].y, fixed[k].z}, s1[3] = {0.0f, 0.0f, 0.0f};  // the SSE path's order
            for (uint32_t x = b; x < e; ++x) {
                const P4& q = src[nbr[x]];
                float* acc = (x - b) % 2 == 0 ? s0 : s1;
                acc[0] += q.x, acc[1] += q.y, acc[2] += q.z;
            }
            const float sx = s0[0] + s1[0], sy = s0[1] + s1[1], sz = s0[2] + s1[2];
            const P4 p = src[k];
            dst[k] = P4{p.x + s * (wd[k] * sx - w[k] * p.x), p.y + s * (wd[k] * sy - w[k] * p.y),
                        p.z + s * (wd[k] * sz - w[k] * p.z), 0.0f};
#endif
        }
    });
}

}  // namespace

std::string_view to_string(SmoothingMethod m) {
    switch (m) {
        case SmoothingMethod::None: return "none";
        case SmoothingMethod::Laplacian: return "laplacian";
        case SmoothingMethod::Taubin: return "taubin";
    }
    return "?";
}

std::string_view to_string(SmoothingSteps s) {
    switch (s) {
        case SmoothingSteps::Uniform: return "uniform";
        case SmoothingSteps::Chebyshev: return "chebyshev";
    }
    return "?";
}

namespace {

/// The step sizes of `def` into `s` (cleared; its capacity reused).
void fill_step_sizes(const SmoothingDef& def, std::vector<float>& s) {
    s.clear();
    const int n = std::max(0, def.iterations);
    if (def.method == SmoothingMethod::None) return;
    if (def.method == SmoothingMethod::Taubin) {
        const float mu = 1.0f / (def.pass_band - 1.0f / def.lambda);
        for (int i = 0; i < n; ++i) s.push_back(i % 2 == 0 ? def.lambda : mu);
        return;
    }
    if (def.steps == SmoothingSteps::Uniform) {
        s.assign(static_cast<size_t>(n), def.lambda);
        return;
    }
    // Chebyshev: the roots r_i = (2 + a) / 2 + (2 - a) / 2 cos(pi (2 i + 1) / (2 N)) of
    // the degree-N polynomial on [a, 2], steps 1 / r_i; small and large steps alternate
    // so the intermediate results stay bounded.
    const double a = def.pass_band, b = 2.0;
    for (int done = 0; done < n;) {
        const int cycle = std::min(kChebyshevCycle, n - done);
        for (int it = 0; it < cycle; ++it) {
            const int root = it % 2 == 0 ? it / 2 : cycle - 1 - it / 2;
            const double r = 0.5 * (b + a) + 0.5 * (b - a) * std::cos(std::numbers::pi * (2 * root + 1) / (2.0 * cycle));
            s.push_back(static_cast<float>(1.0 / r));
        }
        done += cycle;
    }
}

}  // namespace

float SmoothingGround::height(float x, float z) const {
    // Terrain::height_mesh's cell and triangle, without its library (and with the floor of
    // a non-negative number as a truncation: floorf is a call in the portable build, and
    // this runs once per vertex).
    const auto cell = [s = spacing](float x, int n, int& k, float& f) {
        float u = x / s;
        u = !(u >= 0.0f) ? 0.0f : std::min(u, float(n - 1));  // NaN: 0
        k = std::min(static_cast<int>(u), n - 2);
        f = std::min(u - float(k), 1.0f);
    };
    int j = 0, i = 0;
    float u = 0.0f, v = 0.0f;
    cell(x, columns, j, u);
    cell(z, rows, i, v);
    const Vec3* r0 = vertices + size_t(i) * size_t(columns) + size_t(j);
    const Vec3* r1 = r0 + columns;
    const float h00 = r0[0].y, h01 = r0[1].y, h10 = r1[0].y, h11 = r1[1].y;
    if (u + v <= 1.0f) return h00 + u * (h01 - h00) + v * (h10 - h00);
    return h11 + (1.0f - u) * (h10 - h11) + (1.0f - v) * (h01 - h11);
}

std::vector<float> smoothing_step_sizes(const SmoothingDef& def) {
    std::vector<float> s;
    fill_step_sizes(def, s);
    return s;
}

float lone_ball_iso_distance(const KernelDef& k, float threshold) {
    const float centre = kernel_value(k, 0.0f);
    if (!(centre > threshold) || !(k.radius > 0.0f) || !std::isfinite(k.radius)) return 0.0f;
    // The kernel falls monotonically from the centre: bisect r^2 in [0, radius^2].
    float lo = 0.0f, hi = k.radius * k.radius;
    for (int it = 0; it < 40; ++it) {
        const float mid = 0.5f * (lo + hi);
        if (kernel_value(k, mid) > threshold) lo = mid;
        else hi = mid;
    }
    return std::sqrt(0.5f * (lo + hi));
}

size_t SmoothingWorkspace::capacity_bytes() const {
    return (ring_start.capacity() + listed.capacity() + next.capacity() + prev.capacity() + next_m.capacity() +
            moving.capacity() + moving_index.capacity() + fan_counts.capacity()) *
               sizeof(uint32_t) +
           (weight.capacity() + moving_weight.capacity() + step_weight.capacity()) * sizeof(float) +
           (a.capacity() + b.capacity() + orig.capacity() + fixed_sum.capacity()) * sizeof(P4) +
           (inner.capacity() + nbr.capacity()) * sizeof(uint32_t) +
           area_normal.capacity() * sizeof(Vec3) + (volume_term.capacity() + area_len.capacity()) * sizeof(float) +
           step_sizes.capacity() * sizeof(float);
}

namespace {

/// Feature weights (the field behind each vertex; 0 for hidden vertices) and the list of
/// the moving vertices (ws.moving, ws.moving_index).
void feature_weights(const SurfaceMesh& mesh, const SmoothingDef& def, SmoothingWorkspace& ws,
                     const SmoothingField* field, const SmoothingGround* ground) {
    const size_t nv = mesh.positions.size();
    const auto t0 = std::chrono::steady_clock::now();
    ws.weight.resize(nv);
    const SparseField* f = field && def.feature_count > 0.0f ? field->field : nullptr;
    const float depth = f ? lone_ball_iso_distance(field->kernel, field->threshold) : 0.0f;
    const float unit = f ? kernel_value(field->kernel, 0.0f) : 1.0f;
    const SampleGrid& g = f ? f->grid() : SampleGrid{};
    const bool use_field = f && depth > 0.0f && unit > 0.0f && mesh.normals.size() == nv && g.nx >= 2 &&
                           g.ny >= 2 && g.nz >= 2 && g.spacing > 0.0f;
    const float half = 0.5f * def.feature_count, inv_span = 1.0f / std::max(half, 1e-3f);
    const Vec3* pos = mesh.positions.data();
    const Vec3* nrm = mesh.normals.data();
    float* weight = ws.weight.data();
    // Hidden vertices (below the ground) get weight 0 without reading the field.
    const SmoothingGround* gr = ground && ground->vertices && ground->columns >= 2 && ground->rows >= 2 &&
                                        ground->spacing > 0.0f && !def.smooth_hidden
                                    ? ground
                                    : nullptr;
    const auto hidden = [gr](const Vec3& p) { return gr && p.y < gr->height(p.x, p.z); };
    // Per share: its moving vertices, then (offsets) where they go in ws.moving.
    const Shares sh(nv);
    size_t share_moving[Shares::kMax] = {}, share_hidden[Shares::kMax] = {};
    std::optional<FieldProbe> probe;
    if (use_field) probe.emplace(*f);
    const float floor = half * unit;  // at or below it, w = 0: only that much is read
    // The eight-wide twin of the loop below (the same weights, bit for bit): every vertex
    // it can take.
    smoothing_simd::WeightPass simd;
    bool use_simd = !ws.scalar && smoothing_simd::available();
    if (use_simd) {
        simd.pos = &pos[0].x;
        simd.nrm = use_field ? &nrm[0].x : nullptr;
        if (gr) {
            simd.ground = &gr->vertices[0].x;
            simd.columns = gr->columns, simd.rows = gr->rows, simd.spacing = gr->spacing;
        }
        if (use_field) {
            simd.dir = f->directory().data();
            simd.pool = f->allocated_blocks() ? f->block_values(0) : nullptr;
            simd.origin = g.origin, simd.inv = 1.0f / g.spacing;
            simd.hi = Vec3(float(g.nx - 1), float(g.ny - 1), float(g.nz - 1));
            simd.nx2 = g.nx - 2, simd.ny2 = g.ny - 2, simd.nz2 = g.nz - 2;
            simd.bx = f->blocks_x(), simd.by = f->blocks_y();
            simd.depth = depth, simd.unit = unit, simd.half = half, simd.inv_span = inv_span;
            simd.min_weight = kMinWeight;
            if (!simd.pool) simd.dir = nullptr, use_simd = false;  // nothing stored: the scalar loop
        }
        use_simd = use_simd && smoothing_simd::sizes_fit(simd, nv, use_field ? f->allocated_blocks() : 0);
    }
    ws.stats.simd_weights = use_simd;
    sh.run([&, depth, unit, half, inv_span, floor](size_t c, size_t lo, size_t hi) {
        size_t moving = 0, hid = 0;
        if (use_simd) lo = smoothing_simd::weights(simd, lo, hi, weight, moving, hid);
        for (size_t v = lo; v < hi; ++v) {
            float w = 1.0f;
            if (hidden(pos[v])) {
                w = 0.0f;
                ++hid;
            } else if (use_field) {
                const float value = probe->at(pos[v] - depth * nrm[v], floor);
                w = smoothstep01((value / unit - half) * inv_span);
                if (w < kMinWeight) w = 0.0f;
            }
            weight[v] = w;
            moving += w > 0.0f;
        }
        share_moving[c] = moving, share_hidden[c] = hid;
    });
    size_t total = 0;
    for (size_t c = 0; c < sh.count; ++c) {
        const size_t n = share_moving[c];
        share_moving[c] = total;
        total += n;
        ws.stats.hidden += share_hidden[c];
    }
    ws.moving.resize(total);
    ws.moving_index.resize(nv);
    sh.run([&](size_t c, size_t lo, size_t hi) {
        uint32_t at = static_cast<uint32_t>(share_moving[c]);
        for (size_t v = lo; v < hi; ++v) {
            if (weight[v] > 0.0f) {
                ws.moving_index[v] = at;
                ws.moving[at++] = static_cast<uint32_t>(v);
            } else {
                ws.moving_index[v] = kFixed;
            }
        }
    });
    ws.stats.ms_weights = ms_since(t0);

}

/// The fans of the moving vertices and the steps' compact form; false (the mesh left as
/// it is) when the mesh is malformed.
bool prepare_steps(const SurfaceMesh& mesh, SmoothingWorkspace& ws) {
    const size_t nv = mesh.positions.size();
    const auto t0 = std::chrono::steady_clock::now();
    if (!build_fans(mesh, ws)) return false;  // a malformed mesh is left as it is
    // Pin the moving vertices on an open boundary (weight 0: they keep their place); the
    // rest move by w / degree.
    const size_t nm = ws.moving.size();
    ws.moving_weight.resize(nm);
    ws.step_weight.resize(nm);
    // The steps' compact form: per moving vertex its moving neighbours (moving indices,
    // first `inner` entries of its range in nbr) and the sum of the others, which do not
    // move; its position in orig (kept for the volume) and a (the first step's source).
    ws.inner.resize(nm);
    ws.nbr.resize(ws.next.size());
    ws.fixed_sum.resize(nm);
    ws.orig.resize(nm);
    ws.a.resize(nm);
    ws.b.resize(nm);
    for_split(nm, [&](size_t lo, size_t hi) {
        const Vec3* p = mesh.positions.data();
        for (size_t k = lo; k < hi; ++k) {
            const float w = fan_closed(ws, k) ? ws.weight[ws.moving[k]] : 0.0f;
            ws.moving_weight[k] = w;
            const uint32_t b = ws.ring_start[k], e = ws.ring_start[k + 1];
            ws.step_weight[k] = w / static_cast<float>(e - b);
            uint32_t in = b;
            float fx = 0.0f, fy = 0.0f, fz = 0.0f;
            for (uint32_t x = b; x < e; ++x) {
                const uint32_t m = ws.next_m[x];
                if (m != kFixed) {
                    ws.nbr[in++] = m;
                } else {
                    const Vec3& q = p[ws.next[x]];
                    fx += q.x, fy += q.y, fz += q.z;
                }
            }
            ws.inner[k] = in - b;
            ws.fixed_sum[k] = P4{fx, fy, fz, 0.0f};
            const Vec3& q = p[ws.moving[k]];
            ws.orig[k] = ws.a[k] = P4{q.x, q.y, q.z, 0.0f};
        }
    });
    double wsum = 0.0;
    for (size_t k = 0; k < nm; ++k) {
        wsum += ws.moving_weight[k];
        ws.stats.pinned += ws.moving_weight[k] == 0.0f;
    }
    ws.stats.moving = nm - ws.stats.pinned;
    ws.stats.mean_weight = wsum / double(nv);
    ws.stats.ms_rings = ms_since(t0);
    return true;
}

/// The position steps (smoothing_step_sizes), then the smoothed positions into the mesh.
void position_steps(SurfaceMesh& mesh, const SmoothingDef& def, SmoothingWorkspace& ws) {
    const size_t nm = ws.moving.size();
    // Position steps, double-buffered over the moving vertices' compact positions; then
    // the smoothed positions back into the mesh.
    const auto t0 = std::chrono::steady_clock::now();
    P4* src = ws.a.data();
    P4* dst = ws.b.data();
    fill_step_sizes(def, ws.step_sizes);
    for (const float s : ws.step_sizes) {
        laplacian_step(ws, src, dst, s);
        std::swap(src, dst);
    }
    // (src now holds the result.)
    for_split(nm, [&](size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) mesh.positions[ws.moving[k]] = Vec3(src[k].x, src[k].y, src[k].z);
    });
    ws.stats.ms_smooth = ms_since(t0);

}

/// Normals of the moving vertices, the volume given back, the normal passes.
void normals_and_volume(SurfaceMesh& mesh, const SmoothingDef& def, SmoothingWorkspace& ws) {
    const size_t nv = mesh.positions.size(), nm = ws.moving.size();
    // Normals of the moving vertices from their smoothed fans, and the change of the
    // enclosed volume to first order: the volume is (1/6) sum over the triangles of
    // a . (b x c), whose gradient at a vertex is a sixth of its fan's area normal s_v
    // (sum of (next - v) x (prev - v)), so the steps changed it by about sum over the
    // moving vertices of (p_v after - p_v before) . s_v / 6. On the river frames of
    // the tests that leaves -0.4 and -0.5 % after the volume is given back, where the
    // exact change (a pass over the listed triangles, before and after) left +0.14 and
    // +0.03 %; it cost as much as the normals, and this costs nothing beside them.
    // Then the volume given back along the normals.
    const auto t0 = std::chrono::steady_clock::now();
    if (mesh.normals.size() != nv) mesh.normals.resize(nv, Vec3(0.0f, 1.0f, 0.0f));  // a mesh made elsewhere
    const bool restore = def.method == SmoothingMethod::Laplacian && def.keep_volume;
    ws.area_normal.resize(nm);
    ws.volume_term.resize(nm);
    ws.area_len.resize(nm);
    for_split(nm, [&](size_t lo, size_t hi) {
        const Vec3* p = mesh.positions.data();
        const P4* orig = ws.orig.data();
        for (size_t k = lo; k < hi; ++k) {
            const Vec3 pv = p[ws.moving[k]];
            Vec3 s(0.0f);
            for (uint32_t x = ws.ring_start[k]; x < ws.ring_start[k + 1]; ++x)
                s += glm::cross(p[ws.next[x]] - pv, p[ws.prev[x]] - pv);
            ws.area_normal[k] = s;
            ws.area_len[k] = glm::length(s);
            ws.volume_term[k] = glm::dot(pv - Vec3(orig[k].x, orig[k].y, orig[k].z), s);
        }
    });
    float d = 0.0f;
    if (restore) {
        double wa = 0.0, dv = 0.0;  // sum of w A_v over the moving vertices; 6 x the volume change (in order)
        for (size_t k = 0; k < nm; ++k) {
            wa += double(ws.moving_weight[k]) * double(ws.area_len[k]) / 6.0;
            dv += double(ws.volume_term[k]);
        }
        ws.stats.volume_change = dv / 6.0;
        if (wa > 0.0 && std::isfinite(ws.stats.volume_change)) d = static_cast<float>(-ws.stats.volume_change / wa);
    }
    for_split(nm, [&](size_t lo, size_t hi) {
        for (size_t k = lo; k < hi; ++k) {
            const uint32_t v = ws.moving[k];
            const float len = ws.area_len[k];
            if (len > 0.0f && std::isfinite(len)) mesh.normals[v] = ws.area_normal[k] / len;
            if (d != 0.0f) mesh.positions[v] += (d * ws.moving_weight[k]) * mesh.normals[v];
        }
    });
    for (int it = 0; it < def.normal_iterations; ++it) {
        for_split(nm, [&](size_t lo, size_t hi) {
            for (size_t k = lo; k < hi; ++k) {
                const uint32_t v = ws.moving[k];
                Vec3 s = mesh.normals[v];
                for (uint32_t x = ws.ring_start[k]; x < ws.ring_start[k + 1]; ++x) s += mesh.normals[ws.next[x]];
                const float len = glm::length(s);
                ws.area_normal[k] = len > 0.0f && std::isfinite(len) ? s / len : mesh.normals[v];
            }
        });
        for_split(nm, [&](size_t lo, size_t hi) {
            for (size_t k = lo; k < hi; ++k) mesh.normals[ws.moving[k]] = ws.area_normal[k];
        });
    }
    ws.stats.ms_normals = ms_since(t0);
}

}  // namespace

void smooth_surface(SurfaceMesh& mesh, const SmoothingDef& def, SmoothingWorkspace& ws, const SmoothingField* field,
                    const SmoothingGround* ground) {
    ws.stats = SmoothingStats{};
    if (def.method == SmoothingMethod::None) return;
    const size_t nv = mesh.positions.size();
    ws.stats.vertices = nv;
    if (nv == 0 || mesh.indices.empty() || def.iterations <= 0) return;

    feature_weights(mesh, def, ws, field, ground);
    if (ws.moving.empty()) return;  // nothing moves: the mesh keeps its normals too
    if (!prepare_steps(mesh, ws)) return;
    position_steps(mesh, def, ws);
    normals_and_volume(mesh, def, ws);
}

}  // namespace mr
