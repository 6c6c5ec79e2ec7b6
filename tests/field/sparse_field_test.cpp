// Tests for the sparse compact-kernel field: the W1 workload's numbers, the kernels, the
// domain rules, a twin against the dense O(balls x samples) sum on random and W1 balls,
// thread-count independence, caps on absurd grids, and reuse of storage across builds.
#include <metariver/sparse_field.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

namespace mr {
namespace {

constexpr double kFloatEps = 1.1920929e-7;  // float's machine epsilon

struct Brute {
    double value = 0.0;  // sum of the kernel over all balls, in double
    double bound = 0.0;  // sum of |terms| (W1: S / (r^2 + 1e-6) + SUB): scales the float error
    int terms = 0;       // balls within the support
};

// The dense reference: every ball against every sample, in double, at the sample's float
// position (origin + spacing * index, as ScalarGrid::position).
Brute brute_force(std::span<const Vec3> balls, const KernelDef& k, const SampleGrid& g, int i, int j, int k_) {
    const Vec3 p = g.origin + g.spacing * Vec3(float(i), float(j), float(k_));
    const double sup2 = static_cast<double>(k.radius) * k.radius;
    Brute b;
    for (const Vec3& c : balls) {
        const glm::dvec3 d = glm::dvec3(p) - glm::dvec3(c);
        const double r2 = glm::dot(d, d);
        if (!(r2 < sup2)) continue;
        ++b.terms;
        if (k.type == FieldKernel::W1) {
            const double s = k.strength / (r2 + 1e-6);
            b.value += std::max(0.0, s - k.subtract);
            b.bound += s + k.subtract;
        } else {
            const double q = 1.0 - r2 / sup2;
            b.value += k.amplitude * q * q * q;
            b.bound += std::abs(k.amplitude);
        }
    }
    return b;
}

// Every sample of the sparse field against the brute force. The sparse field sums floats:
// each term carries a few roundings (difference, squares, sum, division, subtraction:
// <= 8 eps of its magnitude) and each of the `terms` additions up to eps of the partial
// sum, so |sparse - dense| <= (8 + terms) eps * bound. Terms at the very edge of the
// support (r^2 within a rounding of R^2) may be in one sum and not the other; both
// kernels are ~0 there (W1 is clamped at 0 from r^2 = S/SUB - 1e-6 on, poly6 ~ q^3).
void expect_matches_brute_force(const SparseField& f, std::span<const Vec3> balls, const KernelDef& k) {
    const SampleGrid& g = f.grid();
    ScalarGrid dense;
    f.to_dense(dense);
    ASSERT_EQ(dense.values.size(), g.samples());
    size_t bad = 0, nonzero = 0;
    for (int z = 0; z < g.nz; ++z)
        for (int y = 0; y < g.ny; ++y)
            for (int x = 0; x < g.nx; ++x) {
                const Brute b = brute_force(balls, k, g, x, y, z);
                const float got = dense.at(x, y, z);
                ASSERT_EQ(got, f.value(x, y, z));
                const double tol = (8.0 + b.terms) * kFloatEps * b.bound + 1e-30;
                if (!(std::abs(static_cast<double>(got) - b.value) <= tol)) {
                    if (++bad < 5) {
                        ADD_FAILURE() << "sample (" << x << ", " << y << ", " << z << "): sparse " << got
                                      << ", dense " << b.value << ", tolerance " << tol;
                    }
                }
                nonzero += got != 0.0f;
            }
    EXPECT_EQ(bad, 0u);
    if (!balls.empty() && g.samples() > 0) {
        EXPECT_GT(nonzero, 0u);
    }
}

std::vector<Vec3> random_balls(int n, Vec3 lo, Vec3 hi, uint32_t seed) {
    Lcg rng(seed);
    std::vector<Vec3> balls(static_cast<size_t>(n));
    for (Vec3& b : balls) b = Vec3(rng.uniform(lo.x, hi.x), rng.uniform(lo.y, hi.y), rng.uniform(lo.z, hi.z));
    return balls;
}

std::vector<float> dense_values(const SparseField& f) {
    ScalarGrid d;
    f.to_dense(d);
    return d.values;
}

bool bitwise_equal(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

TEST(W1Workload, BallsMatchThePeersCheckValues) {
    const std::vector<Vec3> balls = w1_balls(10000);
    ASSERT_EQ(balls.size(), 10000u);
    // Printed with 9 decimals in ../shared/peers/README.md (+-5e-10); our coordinates are
    // the double values rounded to float, off by at most half an ulp (2^-25 below 1).
    const double tol = std::ldexp(1.0, -25) + 5e-10;
    EXPECT_NEAR(balls[0].x, 0.116322149, tol);
    EXPECT_NEAR(balls[0].y, 0.113238279, tol);
    EXPECT_NEAR(balls[0].z, 0.534524636, tol);
    // Coordinate sums (computed by the peers in double): each float coordinate (< 1) is
    // off by at most 2^-25 from its double, and the sums are printed to 1e-6.
    for (const auto& [n, sum] : {std::pair{50, 79.459106}, {1000, 1493.437325}, {10000, 14935.626684}}) {
        const std::vector<Vec3> b = w1_balls(n);
        double s = 0.0;
        for (const Vec3& p : b) s += double(p.x) + double(p.y) + double(p.z);
        EXPECT_NEAR(s, sum, 3.0 * n * std::ldexp(1.0, -25) + 1e-6) << "N = " << n;
    }
}

TEST(W1Workload, KernelHasIsoAtTheBallRadiusAndTheDocumentedSupport) {
    for (int n : {50, 1000, 10000}) {
        const KernelDef k = w1_kernel_for(n);
        const double r = 0.3 * std::pow(double(n), -1.0 / 3.0);
        EXPECT_EQ(k.type, FieldKernel::W1);
        EXPECT_NEAR(k.strength, 92.0 * r * r, 1e-6 * 92.0 * r * r);  // float rounding of S
        EXPECT_FLOAT_EQ(k.subtract, 12.0f);
        EXPECT_NEAR(k.radius, r * std::sqrt(92.0 / 12.0), 1e-6 * r);  // float rounding of sqrt(S/SUB)
        // A lone ball's value at r: (ISO + SUB) r^2 / (r^2 + 1e-6) - SUB, in float (a few
        // roundings of a value ~92: 1e-5 relative); that is ISO up to the 1e-6 m^2 softening,
        // < 0.6 % here since r^2 >= 1.9e-4.
        const double at_r = 92.0 * r * r / (r * r + 1e-6) - 12.0;
        EXPECT_NEAR(kernel_value(k, float(r * r)), at_r, 1e-5 * 92.0);
        EXPECT_NEAR(at_r, kW1Iso, 0.006 * kW1Iso);
        EXPECT_EQ(kernel_value(k, k.radius * k.radius), 0.0f);
    }
    const SampleGrid g = w1_grid(128);
    EXPECT_EQ(g.nx, 128);
    EXPECT_EQ(g.origin, Vec3(0.0f));
    EXPECT_FLOAT_EQ(g.spacing * 127.0f, 1.0f);
}

TEST(Kernels, Poly6IsSmoothAndCompact) {
    const KernelDef k = poly6_kernel(0.5f, 3.0f);
    EXPECT_EQ(kernel_value(k, 0.0f), 3.0f);
    EXPECT_EQ(kernel_value(k, 0.25f), 0.0f);
    EXPECT_EQ(kernel_value(k, 1.0f), 0.0f);
    EXPECT_FLOAT_EQ(kernel_value(k, 0.0625f), 3.0f * 0.75f * 0.75f * 0.75f);
    EXPECT_TRUE(validate(k));
    EXPECT_FALSE(validate(poly6_kernel(0.0f, 1.0f)));
    EXPECT_FALSE(validate(poly6_kernel(NAN, 1.0f)));
    EXPECT_FALSE(validate(w1_kernel(-1.0f, 12.0f)));
}

// One kernel enum for the field layer: a KernelDef (the sparse field's) takes only the
// compact kernels, and the dense paper field refuses W1 (its strength and subtract are a
// KernelDef's) instead of drawing another kernel.
TEST(Kernels, OneEnumTheCompactOnesForTheSparseFieldTheDenseOnesForThePapers) {
    KernelDef k = poly6_kernel(1.0f, 1.0f);
    for (FieldKernel t : {FieldKernel::InverseSquare, FieldKernel::RadiusOverR}) {
        k.type = t;
        EXPECT_FALSE(validate(k)) << to_string(t);
    }
    EXPECT_TRUE(validate(w1_kernel(2.0f, 12.0f)));
    EXPECT_EQ(to_string(FieldKernel::W1), "w1");
    const std::vector<Vec3> balls = {Vec3(1, 2, 3)};
    ScalarGrid g;
    EXPECT_FALSE(compute_field_paper(balls, FieldDef{.kernel = FieldKernel::W1}, g));
    EXPECT_EQ(g.size(), 0u);
    EXPECT_TRUE(compute_field_paper(balls, FieldDef{.kernel = FieldKernel::RadiusOverR}, g));
    EXPECT_GT(g.size(), 0u);
    // ...and one grid: the dense field's grid is a SampleGrid with values.
    const SampleGrid& geometry = g;
    EXPECT_EQ(geometry.samples(), g.values.size());
}

TEST(SparseField, BallBoundsDomainFollowsThePaperRule) {
    const std::vector<Vec3> balls = {Vec3(1, 2, 3), Vec3(4, 2.5f, 3)};
    FieldDef paper{.resolution = 2.0f, .bounds_offset = 4.0f};
    ScalarGrid dense;
    ASSERT_TRUE(compute_field_paper(balls, paper, dense));
    SparseField f;
    const SparseFieldDef def{.kernel = poly6_kernel(1.0f, 1.0f), .resolution = 2.0f, .bounds_offset = 4.0f};
    ASSERT_TRUE(f.build(balls, def));
    EXPECT_EQ(f.grid().origin, dense.origin);
    EXPECT_EQ(f.grid().spacing, dense.spacing);
    EXPECT_EQ(f.grid().nx, dense.nx);
    EXPECT_EQ(f.grid().ny, dense.ny);
    EXPECT_EQ(f.grid().nz, dense.nz);
    EXPECT_EQ(f.blocks_x(), (dense.nx + 7) / 8);
}

TEST(SparseField, MatchesTheDenseSumOnRandomBalls) {
    struct Case {
        int n;
        KernelDef kernel;
        SparseFieldDef def;
    };
    SampleGrid box;  // a fixed box that cuts through the balls' cloud and misses some of them
    box.origin = Vec3(-0.3f, 0.1f, -0.2f);
    box.spacing = 0.07f;
    box.nx = 27;
    box.ny = 13;
    box.nz = 20;
    std::vector<Case> cases;
    for (KernelDef k : {poly6_kernel(0.25f, 1.5f), w1_kernel(92.0f * 0.1f * 0.1f, 12.0f), poly6_kernel(0.6f, -2.0f)}) {
        for (int n : {1, 7, 60, 300}) {
            cases.push_back({n, k, {.kernel = k, .resolution = 9.0f, .bounds_offset = k.radius}});
            cases.push_back({n, k, {.kernel = k, .domain = DomainMode::FixedBox, .box = box}});
        }
    }
    cases.push_back({40, poly6_kernel(0.05f, 1.0f), {.kernel = poly6_kernel(0.05f, 1.0f), .resolution = 37.0f,
                                                    .bounds_offset = 0.0f}});  // support < 2 samples
    uint32_t seed = 1;
    for (const Case& c : cases) {
        SCOPED_TRACE(::testing::Message() << "n = " << c.n << ", kernel " << to_string(c.kernel.type) << " radius "
                                          << c.kernel.radius << ", domain " << int(c.def.domain));
        const std::vector<Vec3> balls = random_balls(c.n, Vec3(-0.5f, 0.0f, -0.4f), Vec3(1.5f, 1.0f, 1.2f), seed++);
        SparseField f;
        ASSERT_TRUE(f.build(balls, c.def));
        expect_matches_brute_force(f, balls, c.kernel);
        // Absent blocks read 0; stored blocks' min/max bound their samples.
        for (int bk = 0; bk < f.blocks_z(); ++bk)
            for (int bj = 0; bj < f.blocks_y(); ++bj)
                for (int bi = 0; bi < f.blocks_x(); ++bi) {
                    const int32_t s = f.slot(bi, bj, bk);
                    if (s == SparseField::kNoBlock) continue;
                    const float* v = f.block_values(s);
                    EXPECT_EQ(*std::min_element(v, v + 512), f.block_min(s));
                    EXPECT_EQ(*std::max_element(v, v + 512), f.block_max(s));
                }
    }
}

TEST(SparseField, MatchesTheDenseSumOnW1) {
    for (const auto& [n, res] : {std::pair{50, 32}, {1000, 64}}) {
        SCOPED_TRACE(::testing::Message() << "N = " << n << ", R = " << res);
        const std::vector<Vec3> balls = w1_balls(n);
        const KernelDef k = w1_kernel_for(n);
        SparseField f;
        ASSERT_TRUE(f.build(balls, {.kernel = k, .domain = DomainMode::FixedBox, .box = w1_grid(res)}));
        EXPECT_EQ(f.blocks_x(), res / 8);
        expect_matches_brute_force(f, balls, k);
    }
}

TEST(SparseField, ValuesDoNotDependOnTheThreadCount) {
    const std::vector<Vec3> balls = w1_balls(2000);
    const SparseFieldDef def{.kernel = w1_kernel_for(2000), .domain = DomainMode::FixedBox, .box = w1_grid(96)};
    std::vector<float> one, two;
    {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 1);
        SparseField f;
        ASSERT_TRUE(f.build(balls, def));
        one = dense_values(f);
    }
    {
        tbb::global_control gc(tbb::global_control::max_allowed_parallelism, 2);
        SparseField f;
        ASSERT_TRUE(f.build(balls, def));
        two = dense_values(f);
    }
    EXPECT_TRUE(bitwise_equal(one, two));
}

TEST(SparseField, EmptySpaceIsNotStored) {
    // Two small balls in opposite corners of a big box: only their blocks exist.
    const std::vector<Vec3> balls = {Vec3(0.1f), Vec3(9.9f)};
    SampleGrid box{.origin = Vec3(0.0f), .spacing = 0.05f, .nx = 201, .ny = 201, .nz = 201};
    SparseField f;
    ASSERT_TRUE(f.build(balls, {.kernel = poly6_kernel(0.2f, 1.0f), .domain = DomainMode::FixedBox, .box = box}));
    EXPECT_EQ(f.block_count(), 26u * 26u * 26u);
    EXPECT_LE(f.allocated_blocks(), 16u);
    EXPECT_GE(f.allocated_blocks(), 2u);
    EXPECT_EQ(f.value(100, 100, 100), 0.0f);
    EXPECT_GT(f.value(2, 2, 2), 0.5f);
    EXPECT_GT(f.value(198, 198, 198), 0.5f);
}

TEST(SparseField, RefusesAbsurdGridsWithoutAllocating) {
    SparseField f;
    const std::vector<Vec3> balls = {Vec3(0.0f), Vec3(1000.0f)};
    // Ball bounds at 100 samples per metre: 1e15 samples.
    const Status a = f.build(balls, {.kernel = poly6_kernel(1.0f, 1.0f), .resolution = 100.0f});
    EXPECT_FALSE(a);
    EXPECT_NE(a.error().message.find("cap"), std::string::npos) << a.error().message;
    // A fixed box over the cap.
    SampleGrid huge{.spacing = 1.0f, .nx = 100000, .ny = 100000, .nz = 10};
    EXPECT_FALSE(f.build(balls, {.kernel = poly6_kernel(1.0f, 1.0f), .domain = DomainMode::FixedBox, .box = huge}));
    // Balls whose support covers a huge number of blocks each.
    SampleGrid big{.spacing = 0.01f, .nx = 500, .ny = 500, .nz = 500};
    const std::vector<Vec3> many(20000, Vec3(2.5f));
    EXPECT_FALSE(f.build(many, {.kernel = poly6_kernel(10.0f, 1.0f), .domain = DomainMode::FixedBox, .box = big}));
    EXPECT_LT(f.capacity_bytes(), size_t{4} << 20);  // nothing grid-sized was allocated
    EXPECT_EQ(f.grid().samples(), 0u);
    // Bad values.
    EXPECT_FALSE(f.build(std::vector<Vec3>{Vec3(NAN, 0, 0)}, {.kernel = poly6_kernel(1.0f, 1.0f)}));
    EXPECT_FALSE(f.build(balls, {.kernel = poly6_kernel(1.0f, 1.0f), .resolution = 0.0f}));
    SampleGrid bad{.spacing = -1.0f, .nx = 4, .ny = 4, .nz = 4};
    EXPECT_FALSE(f.build(balls, {.kernel = poly6_kernel(1.0f, 1.0f), .domain = DomainMode::FixedBox, .box = bad}));
}

TEST(SparseField, BallsSpreadOverKilometresKeepTheFieldAroundTheMostOfThem) {
    // A fall's 300 balls in a 4 m cluster, 40 drops spread over 9 km, 20 in a second cluster
    // 5 km away: their box at 3 samples per metre would hold ~1e13 samples.
    std::vector<Vec3> balls;
    for (int n = 0; n < 300; ++n) balls.emplace_back(100.0f + float(n % 7) * 0.5f, 50.0f + float(n / 49) * 0.5f, 2000.0f + float((n / 7) % 7) * 0.5f);
    for (int n = 0; n < 40; ++n) balls.emplace_back(float(n) * 230.0f, 10.0f, float(n % 5) * 1800.0f);
    for (int n = 0; n < 20; ++n) balls.emplace_back(5000.0f + float(n) * 0.4f, 30.0f, 5000.0f);
    const SparseFieldDef def{.kernel = poly6_kernel(1.75f, 1.0f), .resolution = 3.0f, .bounds_offset = 1.75f};
    SparseField f;
    ASSERT_FALSE(f.build(balls, def));  // what the field did before: no surface at all
    std::vector<Vec3> kept = balls;
    const size_t left_out = keep_balls_within_cap(kept, def.resolution, def.bounds_offset);
    EXPECT_EQ(left_out + kept.size(), balls.size());
    // The cluster is kept whole, in its order, the far ones are left out.
    ASSERT_GE(kept.size(), 300u);
    EXPECT_LE(kept.size(), 302u);  // and the drops that happen to lie within the window
    EXPECT_EQ(kept[0], balls[0]);
    for (const Vec3& b : kept) EXPECT_LT(glm::distance(b, Vec3(101.5f, 52.0f, 2001.5f)), 1000.0f);
    ASSERT_TRUE(f.build(kept, def));
    EXPECT_LE(f.grid().samples(), kMaxSparseFieldSamples);
    EXPECT_GT(f.allocated_blocks(), 0u);
    // Balls that fit are all kept.
    std::vector<Vec3> near(balls.begin(), balls.begin() + 300);
    EXPECT_EQ(keep_balls_within_cap(near, def.resolution, def.bounds_offset), 0u);
    EXPECT_EQ(near.size(), 300u);
}

TEST(SparseField, NoBallsGiveAnEmptyOrZeroField) {
    SparseField f;
    ASSERT_TRUE(f.build({}, {.kernel = poly6_kernel(1.0f, 1.0f)}));
    EXPECT_EQ(f.grid().samples(), 0u);
    SampleGrid box{.spacing = 0.5f, .nx = 9, .ny = 3, .nz = 17};
    ASSERT_TRUE(f.build({}, {.kernel = poly6_kernel(1.0f, 1.0f), .domain = DomainMode::FixedBox, .box = box}));
    EXPECT_EQ(f.allocated_blocks(), 0u);
    ScalarGrid d;
    f.to_dense(d);
    ASSERT_EQ(d.values.size(), 9u * 3u * 17u);
    EXPECT_TRUE(std::all_of(d.values.begin(), d.values.end(), [](float v) { return v == 0.0f; }));
}

TEST(SparseField, ALevelTermIsAddedToTheStoredBlocksOnlyLinearInHeight) {
    // One ball in a fixed box of 2 x 2 x 2 blocks (16^3 samples, 0.25 m apart): it reaches
    // the blocks at x, y, z < 4 m only. A level at y = 1.3 m over x < 2 m.
    const SampleGrid box{.origin = Vec3(0.0f), .spacing = 0.25f, .nx = 16, .ny = 16, .nz = 16};
    SparseField f;
    ASSERT_TRUE(f.build(std::vector<Vec3>{Vec3(0.9f)}, {.kernel = poly6_kernel(0.5f, 1.0f),
                                                        .domain = DomainMode::FixedBox, .box = box}));
    ASSERT_EQ(f.allocated_blocks(), 1u);
    const std::vector<float> before = dense_values(f);
    f.add_level_term(
        [](float x, float, float& s) {
            s = 1.3f;
            return x < 2.0f;
        },
        0.3f, 0.5f);
    for (int k = 0; k < 16; ++k)
        for (int j = 0; j < 16; ++j)
            for (int i = 0; i < 16; ++i) {
                const float y = 0.25f * float(j), added = f.value(i, j, k) - before[box.index(i, j, k)];
                const bool stored = i < 8 && j < 8 && k < 8;
                const float want = stored && 0.25f * float(i) < 2.0f ? 0.3f * std::clamp(1.0f + (1.3f - y) / 0.5f, 0.0f, 2.0f)
                                                                   : 0.0f;
                ASSERT_NEAR(added, want, 1e-6f) << i << " " << j << " " << k;
            }
    // The block's range follows: its largest value is now at least 2 x 0.3 (deep under the level).
    EXPECT_GE(f.block_max(f.slot(0, 0, 0)), 0.6f);
    // The same on a field copied from a dense grid (its slots' blocks are known there too).
    ScalarGrid d;
    f.to_dense(d);
    SparseField g;
    ASSERT_TRUE(g.from_dense(d));
    g.add_level_term([](float, float, float& s) { s = 0.0f; return true; }, 1.0f, 1.0f);
    EXPECT_NEAR(g.value(1, 0, 1) - f.value(1, 0, 1), 1.0f, 1e-6f);  // y = 0 is at the level
}

TEST(SparseField, ALevelTermFromAColumnTableEqualsTheFunctions) {
    // 300 balls in a 40 x 24 x 36 box (several blocks, partial ones at the far sides); a level
    // varying per column, absent (NaN / false) in every third column: the table and the
    // function give the same bits, and a table too short for the grid adds nothing.
    const SampleGrid box{.origin = Vec3(-1.0f, 0.5f, 2.0f), .spacing = 0.1f, .nx = 40, .ny = 24, .nz = 36};
    std::vector<Vec3> balls;
    for (int n = 0; n < 300; ++n)
        balls.emplace_back(-0.8f + 3.5f * float((n * 37) % 101) / 101.0f, 0.6f + 2.0f * float((n * 53) % 97) / 97.0f,
                           2.2f + 3.0f * float((n * 71) % 89) / 89.0f);
    const SparseFieldDef def{.kernel = poly6_kernel(0.3f, 1.0f), .domain = DomainMode::FixedBox, .box = box};
    SparseField a, b;
    ASSERT_TRUE(a.build(balls, def));
    ASSERT_TRUE(b.build(balls, def));
    ASSERT_GT(a.allocated_blocks(), 4u);
    const auto level = [](int i, int k) { return 0.9f + 0.013f * float(i) + 0.007f * float(k * k % 17); };
    std::vector<float> table(size_t(box.nx) * size_t(box.nz));
    for (int k = 0; k < box.nz; ++k)
        for (int i = 0; i < box.nx; ++i)
            table[size_t(i) + size_t(box.nx) * size_t(k)] = (i + k) % 3 == 0 ? std::nanf("") : level(i, k);
    a.add_level_term(
        [&](float x, float z, float& s) {
            const int i = int(std::lround((x - box.origin.x) / box.spacing)), k = int(std::lround((z - box.origin.z) / box.spacing));
            s = level(i, k);
            return (i + k) % 3 != 0;
        },
        0.5f, 0.2f);
    b.add_level_term(std::span<const float>(table), 0.5f, 0.2f);
    const std::vector<float> va = dense_values(a), vb = dense_values(b);
    EXPECT_TRUE(bitwise_equal(va, vb));
    for (size_t s = 0; s < a.allocated_blocks(); ++s) {
        EXPECT_EQ(a.block_min(int32_t(s)), b.block_min(int32_t(s)));
        EXPECT_EQ(a.block_max(int32_t(s)), b.block_max(int32_t(s)));
    }
    SparseField c;
    ASSERT_TRUE(c.build(balls, def));
    const std::vector<float> before = dense_values(c);
    c.add_level_term(std::span<const float>(table).first(table.size() - 1), 0.5f, 0.2f);
    EXPECT_TRUE(bitwise_equal(before, dense_values(c)));
    EXPECT_FALSE(bitwise_equal(before, va));  // the term did add something
}

TEST(SparseField, SteadyStateBuildsReuseStorage) {
    const std::vector<Vec3> balls = w1_balls(1000);
    const SparseFieldDef def{.kernel = w1_kernel_for(1000), .domain = DomainMode::FixedBox, .box = w1_grid(64)};
    SparseField f;
    ASSERT_TRUE(f.build(balls, def));
    const size_t bytes = f.capacity_bytes();
    const std::vector<float> first = dense_values(f);
    const float* block0 = f.block_values(0);
    ASSERT_TRUE(f.build(balls, def));
    EXPECT_EQ(f.capacity_bytes(), bytes);
    EXPECT_EQ(f.block_values(0), block0);
    EXPECT_TRUE(bitwise_equal(first, dense_values(f)));
    // A smaller frame keeps the capacity (grows, never shrinks).
    ASSERT_TRUE(f.build(std::span(balls).first(10), def));
    EXPECT_EQ(f.capacity_bytes(), bytes);
}

}  // namespace
}  // namespace mr
