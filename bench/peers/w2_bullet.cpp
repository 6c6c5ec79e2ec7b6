// metariver peer driver, W2 'spheres on terrain' with Bullet 3.24 (Debian libbullet-dev,
// single precision, single-threaded). W2 is defined in ../shared/peers/README.md.
//
// N spheres (radius 0.5, mass 1) from the spawn lattice fall onto the 257 x 257 valley,
// given to Bullet as a btHeightfieldTerrainShape ("hf") or as a btBvhTriangleMeshShape of
// the same two-triangles-per-cell surface ("mesh"). Bullet's defaults otherwise: Dbvt
// broadphase, sequential impulse solver (10 iterations), friction 0.5, restitution 0, no
// CCD, sleeping on unless --nosleep; stepSimulation(1/60, 1, 1/60) = one internal step.
//
// Metrics: ms per step (median over steps settle+1..steps), the fall (first `settle` steps)
// as a total, and after the last step: centres below the surface (tunneled), penetration of
// the surface by more than 0.25 along its normal, centres outside the 256 x 256 rectangle,
// active (awake) bodies.
//
// Usage: bench_w2_bullet --n N [--shape hf|mesh] [--steps 600] [--settle 120] [--nosleep] [--seed 12345]
// Prints one JSON line (keys as ../shared/peers/w2_bullet.cpp). Exit 2 on bad options,
// 1 when a self-check (random numbers, spawn height, terrain ray casts) fails.
#include <btBulletDynamicsCommon.h>
#include <BulletCollision/CollisionShapes/btHeightfieldTerrainShape.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

namespace {

constexpr int kSide = 257;         // height samples per axis; sample (i, j) at world (x, z) = (i, j)
constexpr float kRadius = 0.5f;
constexpr int kLatticeX = 40, kLatticeZ = 141;
constexpr double kSpacing = 1.25, kLatticeX0 = 104.0, kLatticeZ0 = 40.0;

[[noreturn]] void fail(int code, const std::string& msg) {
    std::fprintf(stderr, "bench_w2_bullet: %s\n", msg.c_str());
    std::exit(code);
}

struct Lcg {  // the shared 32-bit LCG (Numerical Recipes constants)
    uint32_t state;
    double next() {
        state = 1664525u * state + 1013904223u;
        return double(state) / 4294967296.0;
    }
};

double valley(double x, double z) {  // h(x, z) of the README
    const double pi = 3.14159265358979323846;
    const double u = (x - 128.0) / 128.0;
    const double centre = 128.0 + 16.0 * std::sin(2.0 * pi * z / 128.0);
    const double a = std::max(0.0, 1.0 - z / 24.0);
    const double b = std::max(0.0, 1.0 - (256.0 - z) / 24.0);
    const double c = (x - centre) / 8.0;
    return 40.0 * u * u + 10.0 * z / 256.0 - 4.0 * std::exp(-c * c) + 30.0 * a * a + 30.0 * b * b;
}

struct Heights {
    std::vector<float> h = std::vector<float>(size_t(kSide) * kSide);
    float at(int i, int j) const { return h[size_t(j) * kSide + i]; }
    /// Height of the triangulated surface: per cell the diagonal (i, j+1)-(i+1, j), Bullet's
    /// default heightfield split (the mesh uses the same triangles).
    double surface(double x, double z) const {
        const int i = std::clamp(int(std::floor(x)), 0, kSide - 2);
        const int j = std::clamp(int(std::floor(z)), 0, kSide - 2);
        const double fx = x - i, fz = z - j;
        if (fx + fz <= 1.0)
            return at(i, j) + fx * (at(i + 1, j) - at(i, j)) + fz * (at(i, j + 1) - at(i, j));
        return at(i + 1, j + 1) + (1.0 - fx) * (at(i, j + 1) - at(i + 1, j + 1)) +
               (1.0 - fz) * (at(i + 1, j) - at(i + 1, j + 1));
    }
};

double seconds() {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

struct Options {
    int n = 1000, steps = 600, settle = 120;
    uint32_t seed = 12345u;
    bool sleeping = true;
    std::string shape = "hf";
};

int to_int(const std::string& opt, const std::string& v, int lo, int hi) {
    char* end = nullptr;
    const long x = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || x < lo || x > hi)
        fail(2, opt + ": must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "] (got '" + v + "')");
    return int(x);
}

Options parse(int argc, char** argv) {
    Options o;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) fail(2, "missing value for " + a);
            return argv[++i];
        };
        if (a == "--n") o.n = to_int(a, value(), 1, 10'000'000);
        else if (a == "--shape") o.shape = value();
        else if (a == "--steps") o.steps = to_int(a, value(), 1, 1'000'000);
        else if (a == "--settle") o.settle = to_int(a, value(), 0, 1'000'000);
        else if (a == "--seed") o.seed = uint32_t(to_int(a, value(), 0, 2147483647));
        else if (a == "--nosleep") o.sleeping = false;
        else fail(2, "unknown option " + a);
    }
    if (o.shape != "hf" && o.shape != "mesh") fail(2, "--shape: must be hf or mesh (got '" + o.shape + "')");
    return o;
}

double median_of(std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::sort(v.begin(), v.end());
    const size_t m = v.size() / 2;
    return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace

int main(int argc, char** argv) {
    const Options o = parse(argc, argv);

    // Self-check of the random numbers: with seed 12345 the first three draws, mapped as W1
    // maps them (0.1 + 0.8 u), are the README's first ball.
    {
        Lcg l{12345u};
        const double want[3] = {0.116322149, 0.113238279, 0.534524636};
        for (double w : want)
            if (std::fabs(0.1 + 0.8 * l.next() - w) > 1e-9) fail(1, "LCG check failed against the README's ball0");
    }

    const double setup0 = seconds();
    Heights hs;
    float hmin = 1e30f, hmax = -1e30f;
    for (int j = 0; j < kSide; ++j)
        for (int i = 0; i < kSide; ++i) {
            const float h = float(valley(i, j));
            hs.h[size_t(j) * kSide + i] = h;
            hmin = std::min(hmin, h);
            hmax = std::max(hmax, h);
        }

    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher(&config);
    btDbvtBroadphase broadphase;
    btSequentialImpulseConstraintSolver solver;
    btDiscreteDynamicsWorld world(&dispatcher, &broadphase, &solver, &config);
    world.setGravity(btVector3(0.0f, -9.82f, 0.0f));

    // Terrain.
    std::unique_ptr<btCollisionShape> ground;
    std::unique_ptr<btTriangleIndexVertexArray> triangles;
    std::vector<btScalar> vertices;
    std::vector<int> indices;
    btTransform groundXf = btTransform::getIdentity();
    if (o.shape == "hf") {
        ground = std::make_unique<btHeightfieldTerrainShape>(kSide, kSide, hs.h.data(), 1.0f, hmin, hmax, 1, PHY_FLOAT,
                                                             false);
        // Bullet centres a heightfield on its bounding box; move it so sample (i, j) is at (i, h, j).
        groundXf.setOrigin(btVector3(0.5f * (kSide - 1), 0.5f * (hmin + hmax), 0.5f * (kSide - 1)));
    } else {
        vertices.reserve(size_t(kSide) * kSide * 3);
        for (int j = 0; j < kSide; ++j)
            for (int i = 0; i < kSide; ++i) {
                vertices.push_back(btScalar(i));
                vertices.push_back(hs.at(i, j));
                vertices.push_back(btScalar(j));
            }
        indices.reserve(size_t(kSide - 1) * (kSide - 1) * 6);
        for (int j = 0; j + 1 < kSide; ++j)
            for (int i = 0; i + 1 < kSide; ++i) {
                const int a = j * kSide + i, b = a + 1, c = a + kSide, d = c + 1;  // (i,j) (i+1,j) (i,j+1) (i+1,j+1)
                for (int v : {a, c, b, b, c, d}) indices.push_back(v);
            }
        triangles = std::make_unique<btTriangleIndexVertexArray>(int(indices.size() / 3), indices.data(),
                                                                 int(3 * sizeof(int)), kSide * kSide, vertices.data(),
                                                                 int(3 * sizeof(btScalar)));
        ground = std::make_unique<btBvhTriangleMeshShape>(triangles.get(), true, true);
    }
    btRigidBody groundBody(btRigidBody::btRigidBodyConstructionInfo(0.0f, nullptr, ground.get()));
    groundBody.setWorldTransform(groundXf);
    world.addRigidBody(&groundBody);

    // Self-check of the terrain: vertical rays hit the analytic triangulated surface.
    double rayErr = 0.0;
    int rayMiss = 0;
    {
        Lcg l{o.seed ^ 0x9e3779b9u};
        for (int k = 0; k < 2000; ++k) {
            const double x = 1.0 + 254.0 * l.next(), z = 1.0 + 254.0 * l.next();
            const btVector3 from(btScalar(x), 200.0f, btScalar(z)), to(btScalar(x), -200.0f, btScalar(z));
            btCollisionWorld::ClosestRayResultCallback hit(from, to);
            world.rayTest(from, to, hit);
            if (!hit.hasHit()) {
                ++rayMiss;
                continue;
            }
            rayErr = std::max(rayErr, std::fabs(double(hit.m_hitPointWorld.y()) - hs.surface(x, z)));
        }
        if (rayMiss > 0 || rayErr > 1e-3)
            fail(1, "terrain ray check failed: " + std::to_string(rayMiss) + " misses, max error " + std::to_string(rayErr));
    }

    // Spheres: lattice 40 x 141 per layer, spacing 1.25, lowest layer 2 above the highest
    // terrain under the lattice footprint (12 by the README), jitter (next() - 0.5) * 0.2.
    double under = -1e30;
    for (int iz = 0; iz < kLatticeZ; ++iz)
        for (int ix = 0; ix < kLatticeX; ++ix)
            for (int a = -2; a <= 2; ++a)
                for (int b = -2; b <= 2; ++b)
                    under = std::max(under, valley(kLatticeX0 + ix * kSpacing + 0.3 * a, kLatticeZ0 + iz * kSpacing + 0.3 * b));
    const double y0 = std::ceil(under) + 2.0;
    if (y0 != 12.0) fail(1, "spawn height y0 = " + std::to_string(y0) + ", the README says 12");

    btSphereShape ball(kRadius);
    btVector3 inertia(0.0f, 0.0f, 0.0f);
    ball.calculateLocalInertia(1.0f, inertia);
    std::vector<std::unique_ptr<btDefaultMotionState>> motion;
    std::vector<std::unique_ptr<btRigidBody>> spheres;
    motion.reserve(size_t(o.n));
    spheres.reserve(size_t(o.n));
    Lcg jitter{o.seed};
    for (int k = 0; k < o.n; ++k) {
        const int layer = k / (kLatticeX * kLatticeZ), rest = k % (kLatticeX * kLatticeZ);
        const int iz = rest / kLatticeX, ix = rest % kLatticeX;
        const double jx = (jitter.next() - 0.5) * 0.2;
        const double jy = (jitter.next() - 0.5) * 0.2;
        const double jz = (jitter.next() - 0.5) * 0.2;
        btTransform t = btTransform::getIdentity();
        t.setOrigin(btVector3(btScalar(kLatticeX0 + ix * kSpacing + jx), btScalar(y0 + layer * kSpacing + jy),
                              btScalar(kLatticeZ0 + iz * kSpacing + jz)));
        motion.push_back(std::make_unique<btDefaultMotionState>(t));
        spheres.push_back(std::make_unique<btRigidBody>(
            btRigidBody::btRigidBodyConstructionInfo(1.0f, motion.back().get(), &ball, inertia)));
        if (!o.sleeping) spheres.back()->setActivationState(DISABLE_DEACTIVATION);
        world.addRigidBody(spheres.back().get());
    }
    const double setupMs = (seconds() - setup0) * 1e3;

    // Simulate.
    auto awake = [&] {
        return int(std::count_if(spheres.begin(), spheres.end(), [](const auto& b) { return b->isActive(); }));
    };
    const btScalar dt = 1.0f / 60.0f;
    std::vector<double> stepMs;
    stepMs.reserve(size_t(o.steps));
    int active120 = -1, active300 = -1;
    const double sim0 = seconds();
    for (int s = 1; s <= o.steps; ++s) {
        const double t0 = seconds();
        world.stepSimulation(dt, 1, dt);
        stepMs.push_back((seconds() - t0) * 1e3);
        if (s == 120) active120 = awake();
        if (s == 300) active300 = awake();
    }
    const double simS = seconds() - sim0;
    const int activeEnd = awake();

    // Outcome after the last step.
    int below = 0, deep = 0, outside = 0;
    double minY = 1e30, sumY = 0.0;
    for (const auto& b : spheres) {
        const btVector3 p = b->getWorldTransform().getOrigin();
        minY = std::min(minY, double(p.y()));
        sumY += p.y();
        if (p.x() < 0.0f || p.x() > float(kSide - 1) || p.z() < 0.0f || p.z() > float(kSide - 1)) {
            ++outside;
            continue;
        }
        const double h = hs.surface(p.x(), p.z());
        if (p.y() < h) ++below;
        const double e = 1e-3;
        const double gx = (hs.surface(p.x() + e, p.z()) - hs.surface(p.x() - e, p.z())) / (2.0 * e);
        const double gz = (hs.surface(p.x(), p.z() + e) - hs.surface(p.x(), p.z() - e)) / (2.0 * e);
        const double ny = 1.0 / std::sqrt(1.0 + gx * gx + gz * gz);  // y of the facet's unit normal
        if (kRadius - (p.y() - h) * ny > 0.25) ++deep;                // depth along the normal
    }

    const int settle = std::min(o.settle, o.steps);
    const std::vector<double> measured(stepMs.begin() + settle, stepMs.end());
    std::vector<double> sorted = measured;
    std::sort(sorted.begin(), sorted.end());
    auto pct = [&](double q) {
        return sorted.empty() ? 0.0 : sorted[std::min(sorted.size() - 1, size_t(q * double(sorted.size())))];
    };
    const double mean = sorted.empty() ? 0.0 : std::accumulate(sorted.begin(), sorted.end(), 0.0) / double(sorted.size());
    const double fallMs = std::accumulate(stepMs.begin(), stepMs.begin() + settle, 0.0);

    std::printf(
        "{\"bench\":\"W2\",\"peer\":\"Bullet %d btDiscreteDynamicsWorld\",\"shape\":\"%s\",\"n\":%d,"
        "\"sleep\":%s,\"threads\":1,\"steps\":%d,\"settle\":%d,\"spawn_y0\":%.1f,"
        "\"ms_step_median\":%.3f,\"ms_step_mean\":%.3f,\"ms_step_p10\":%.3f,\"ms_step_p90\":%.3f,"
        "\"ms_step_min\":%.3f,\"ms_step_max\":%.3f,\"ms_first_%d_steps_total\":%.1f,\"sim_total_s\":%.2f,"
        "\"setup_ms\":%.1f,\"active_at_120\":%d,\"active_at_300\":%d,\"active_at_end\":%d,"
        "\"tunneled_below_surface\":%d,\"penetration_gt_quarter\":%d,\"escaped_domain\":%d,"
        "\"min_y\":%.2f,\"mean_y\":%.3f,\"ray_check_max_err\":%.2e,\"ray_check_miss\":%d}\n",
        btGetVersion(), o.shape.c_str(), o.n, o.sleeping ? "true" : "false", o.steps, settle, y0,
        median_of(measured), mean, pct(0.1), pct(0.9), sorted.empty() ? 0.0 : sorted.front(),
        sorted.empty() ? 0.0 : sorted.back(), settle, fallMs, simS, setupMs, active120, active300, activeEnd, below,
        deep, outside, minY, sumY / std::max(1, o.n), rayErr, rayMiss);
    std::fflush(stdout);

    for (auto& b : spheres) world.removeRigidBody(b.get());
    world.removeRigidBody(&groundBody);
    return 0;
}
