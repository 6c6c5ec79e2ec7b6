#include <metariver/neighbor_grid.h>
#include <metariver/particles.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <set>

namespace mr {
namespace {

Particles random_particles(size_t n, uint32_t seed, Vec3 extent, float inactive_fraction = 0.1f) {
    Particles p;
    p.resize(n);
    Lcg rng(seed);
    for (size_t i = 0; i < n; ++i) {
        p.position[i] = Vec3(rng.uniform(0, extent.x), rng.uniform(0, extent.y), rng.uniform(0, extent.z));
        p.active[i] = rng.next() >= inactive_fraction;
    }
    return p;
}


/// Cell of position v as the grid computes it (same float arithmetic), relative to the
/// active particles' box corner; coordinates beyond 2^21 cells merge into the last.
std::array<int, 3> cell_of(const Vec3& v, const Vec3& origin, float cell) {
    const float inv = 1.0f / cell;
    const auto c = [&](float x, float o) { return std::min(int(std::floor((x - o) * inv)), 0x1FFFFF); };
    return {c(v.x, origin.x), c(v.y, origin.y), c(v.z, origin.z)};
}

/// The particles of the 27 cells around cell c, cell by cell (z, y, x), each cell's in
/// index order.
std::vector<uint32_t> around(const std::map<std::array<int, 3>, std::vector<uint32_t>>& by_cell,
                             const std::array<int, 3>& c) {
    std::vector<uint32_t> want;
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const auto it = by_cell.find({c[0] + dx, c[1] + dy, c[2] + dz});
                if (it != by_cell.end()) want.insert(want.end(), it->second.begin(), it->second.end());
            }
    return want;
}

/// Builds a grid and checks it against brute force: every cell is exactly one run (its
/// particles in index order), order() is a stable sort by bucket, and every run's
/// neighbour ranges hold exactly the binned particles of the 27 cells around it, each
/// once, in at most 27 ranges; for_each_candidate agrees. Returns the layout used.
NeighborGrid::Layout check_against_brute_force(const Particles& p, float cell) {
    NeighborGrid g;
    g.build(p.position, p.active, cell);
    Aabb box;
    std::vector<uint32_t> binned;
    for (size_t i = 0; i < p.size(); ++i)
        if (p.active[i]) {
            box.grow(p.position[i]);
            binned.push_back(static_cast<uint32_t>(i));
        }
    const auto order = g.order();
    EXPECT_EQ(order.size(), binned.size());
    if (order.size() != binned.size()) return g.layout();
    for (size_t k = 1; k < order.size(); ++k) {
        const uint32_t a = g.bucket_of(order[k - 1]), b = g.bucket_of(order[k]);
        // (A hash bucket is further ordered by cell; runs are checked for index order below.)
        if (g.layout() == NeighborGrid::Layout::Hashed)
            EXPECT_LE(a, b) << "not sorted by bucket at " << k;
        else
            EXPECT_TRUE(a < b || (a == b && order[k - 1] < order[k])) << "not a stable sort by bucket at " << k;
        EXPECT_LT(b, g.bucket_count());
    }
    const auto sx = g.sorted_x(), sy = g.sorted_y(), sz = g.sorted_z();
    for (size_t k = 0; k < order.size(); ++k) {
        EXPECT_EQ(sx[k], p.position[order[k]].x);
        EXPECT_EQ(sy[k], p.position[order[k]].y);
        EXPECT_EQ(sz[k], p.position[order[k]].z);
    }
    std::map<std::array<int, 3>, std::vector<uint32_t>> by_cell;  // particles in index order
    for (uint32_t i : binned) by_cell[cell_of(p.position[i], box.min, cell)].push_back(i);
    EXPECT_EQ(g.run_count(), by_cell.size()) << "one run per occupied cell";
    EXPECT_EQ(g.run_start(0), 0u);
    EXPECT_EQ(g.run_start(g.run_count()), order.size());
    std::set<std::array<int, 3>> seen_cells;
    for (size_t r = 0; r < g.run_count(); ++r) {
        const std::array<int, 3> c = cell_of(p.position[order[g.run_start(r)]], box.min, cell);
        EXPECT_TRUE(seen_cells.insert(c).second) << "cell split over two runs";
        const std::vector<uint32_t> run(order.begin() + g.run_start(r), order.begin() + g.run_start(r + 1));
        EXPECT_EQ(run, by_cell[c]) << "run " << r;
        std::vector<uint32_t> want = around(by_cell, c);
        std::sort(want.begin(), want.end());
        std::vector<uint32_t> got;
        int ranges = 0;
        g.for_each_neighbor_range(r, [&](uint32_t s, uint32_t e) {
            ++ranges;
            EXPECT_LE(s, e);
            EXPECT_LE(e, order.size());
            for (uint32_t k = s; k < e; ++k) got.push_back(order[k]);
        });
        EXPECT_LE(ranges, 27);
        std::sort(got.begin(), got.end());
        EXPECT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "particle visited twice, run " << r;
        EXPECT_EQ(got, want) << "run " << r << " cell " << c[0] << "," << c[1] << "," << c[2];
        if (got != want) break;
        if (g.layout() != NeighborGrid::Layout::Hashed) {  // no foreign candidates either
            std::vector<uint32_t> cand;
            g.for_each_candidate(p.position[run[0]], [&](uint32_t j) { cand.push_back(j); });
            std::sort(cand.begin(), cand.end());
            EXPECT_EQ(cand, want) << "for_each_candidate, run " << r;
        }
    }
    return g.layout();
}

TEST(NeighborGrid, CandidatesContainEveryParticleWithinOneCellDenseAndHashed) {
    struct Case {
        size_t n;
        Vec3 extent;
        float cell;
    };
    // Compact clouds give a dense grid; clouds spread far (> 32 cells per particle, and
    // too sparse for blocks: > 64 cells of 8^3 or 16^3 blocks per particle) force the
    // hash table.
    for (const Case& c : {Case{500, Vec3(5, 5, 5), 0.7f}, Case{2000, Vec3(300, 2, 300), 0.5f},
                          Case{300, Vec3(1e4f, 1e4f, 1e4f), 50.0f}}) {
        Particles p = random_particles(c.n, 17, c.extent);
        NeighborGrid g;
        g.build(p.position, p.active, c.cell);
        const bool hashed = g.hashed();
        for (size_t i = 0; i < p.size(); i += 3) {
            std::set<uint32_t> cand;
            g.for_each_candidate(p.position[i], [&](uint32_t j) {
                EXPECT_TRUE(p.active[j]) << "inactive particles are never binned";
                EXPECT_TRUE(cand.insert(j).second) << "candidate visited twice";
            });
            for (size_t j = 0; j < p.size(); ++j) {
                if (p.active[j] && glm::length(p.position[i] - p.position[j]) < c.cell) {
                    ASSERT_TRUE(cand.count(static_cast<uint32_t>(j))) << "missed neighbour, hashed=" << hashed;
                }
            }
        }
        if (c.n != 500) {
            EXPECT_TRUE(hashed);
        }
        if (c.n == 500) {
            EXPECT_FALSE(hashed);
        }
    }
}

TEST(NeighborGrid, BlockedLayoutFindsExactlyTheBruteForceNeighbours) {
    using L = NeighborGrid::Layout;
    struct Case {
        size_t n;
        Vec3 extent;
        float cell;
        float inactive;
    };
    // Spread-out clouds of various densities: ~1 particle per 40 to 500 cells, flat
    // sheets like spheres on a valley floor, and thin rods along each axis.
    for (const Case& c : {Case{3000, Vec3(60, 60, 60), 1.0f, 0.1f}, Case{2000, Vec3(100, 10, 100), 0.8f, 0.0f},
                          Case{10000, Vec3(400, 3, 400), 1.0f, 0.2f}, Case{800, Vec3(150, 40, 150), 1.7f, 0.5f},
                          Case{400, Vec3(3000, 5, 5), 1.0f, 0.0f}, Case{400, Vec3(5, 3000, 5), 1.0f, 0.0f},
                          Case{400, Vec3(5, 5, 3000), 1.0f, 0.0f}}) {
        const Particles p = random_particles(c.n, 29, c.extent, c.inactive);
        EXPECT_EQ(check_against_brute_force(p, c.cell), L::Blocked) << c.n << " particles";
    }
}

TEST(NeighborGrid, BlockedLayoutHandlesCellsOnBlockFaces) {
    // A lattice of particles in the cells on both sides of block faces (cells 3|4, 7|8,
    // 15|16, 31|32 of 4^3 and 8^3 blocks), some exactly on cell boundaries, plus a far
    // corner so the box is too large for a dense grid (first 4^3 blocks, then 8^3).
    for (const Vec3 corner : {Vec3(60.0f, 60.0f, 60.0f), Vec3(100.0f, 40.0f, 100.0f)}) {
        std::vector<Vec3> pts = {Vec3(0.0f), corner};
        for (int copy = 0; copy < 3; ++copy)  // several particles per cell
            for (float a : {3.0f, 3.5f, 4.0f, 4.5f, 7.5f, 8.0f, 15.5f, 16.0f, 31.0f, 32.0f})
                for (float b : {3.5f, 4.0f, 8.0f, 16.5f})
                    for (float d : {0.0f, 4.0f, 7.99f, 8.0f}) {
                        pts.push_back(Vec3(a, b, d));
                        pts.push_back(Vec3(b, d, a));
                        pts.push_back(Vec3(d, a, b));
                    }
        Particles p;
        p.resize(pts.size());
        for (size_t i = 0; i < pts.size(); ++i) {
            p.position[i] = pts[i];
            p.active[i] = 1;
        }
        EXPECT_EQ(check_against_brute_force(p, 1.0f), NeighborGrid::Layout::Blocked);
    }
    // Clusters far apart: the directory needs 8^3, then 16^3 blocks to stay small; the
    // clusters straddle block faces.
    Particles q = random_particles(2000, 5, Vec3(3, 3, 3), 0.0f);
    for (size_t i = 0; i < q.size(); ++i)
        q.position[i] += Vec3(float(i % 4) * 40.0f, float(i % 3) * 60.0f, float(i % 5) * 30.0f);
    EXPECT_EQ(check_against_brute_force(q, 1.0f), NeighborGrid::Layout::Blocked);
    Particles c = random_particles(2000, 6, Vec3(4, 4, 4), 0.0f);
    for (size_t i = 0; i < c.size(); ++i)
        c.position[i] += Vec3(float(i % 2) * 190.0f, float((i / 2) % 2) * 190.0f, float((i / 4) % 2) * 190.0f);
    EXPECT_EQ(check_against_brute_force(c, 1.0f), NeighborGrid::Layout::Blocked);
}

TEST(NeighborGrid, CandidatesAroundAnyPointComeAsRowsInTheCellsOrder) {
    // The foam's points lie anywhere, also beside and above the fluid's box: the walk
    // around a point must give exactly the binned particles of the 27 cells around the
    // point's cell, in the order of those cells (z, y, x) and each cell's index order,
    // as x-rows (at most 18 ranges) in a dense or blocked grid.
    using L = NeighborGrid::Layout;
    struct Case {
        size_t n;
        Vec3 extent;
        float cell;
        L layout;
    };
    for (const Case& c : {Case{500, Vec3(5, 5, 5), 0.7f, L::Dense}, Case{3000, Vec3(60, 60, 60), 1.0f, L::Blocked},
                          Case{2000, Vec3(100, 10, 100), 0.8f, L::Blocked}}) {
        const Particles p = random_particles(c.n, 41, c.extent, 0.1f);
        NeighborGrid g;
        g.build(p.position, p.active, c.cell);
        ASSERT_EQ(g.layout(), c.layout);
        Aabb box;
        std::map<std::array<int, 3>, std::vector<uint32_t>> by_cell;
        for (size_t i = 0; i < p.size(); ++i)
            if (p.active[i]) box.grow(p.position[i]);
        for (size_t i = 0; i < p.size(); ++i)
            if (p.active[i]) by_cell[cell_of(p.position[i], box.min, c.cell)].push_back(uint32_t(i));
        Lcg rng(7);
        const Vec3 margin(3.0f * c.cell);
        int outside = 0;
        for (int t = 0; t < 400; ++t) {
            Vec3 q(rng.uniform(box.min.x - margin.x, box.max.x + margin.x),
                   rng.uniform(box.min.y - margin.y, box.max.y + margin.y),
                   rng.uniform(box.min.z - margin.z, box.max.z + margin.z));
            if (t % 4 == 0) q = p.position[size_t(t) % p.size()] + Vec3(0.0f, float(t % 3) * c.cell, 0.0f);
            outside += !box.contains(q);
            const std::array<int, 3> cq = cell_of(q, box.min, c.cell);
            const std::vector<uint32_t> want = around(by_cell, cq);
            std::vector<uint32_t> got, slots;
            int ranges = 0;
            const auto order = g.order();
            g.for_each_candidate_range(q, [&](uint32_t s, uint32_t e) {
                ++ranges;
                EXPECT_LT(s, e) << "empty range";
                for (uint32_t k = s; k < e; ++k) got.push_back(order[k]);
            });
            g.for_each_candidate_slot(q, [&](uint32_t k) { slots.push_back(order[k]); });
            EXPECT_LE(ranges, 18);
            EXPECT_EQ(got, want) << "point " << t;
            EXPECT_EQ(slots, want) << "point " << t;
            if (got != want) break;
        }
        EXPECT_GT(outside, 50) << "the points must also lie outside the box";
    }
}

TEST(NeighborGrid, HugeOrSparseBoxesFallBackToTheHashExactly) {
    // One particle per 16^3 block or sparser, or a box beyond 2M cells a side (far cells
    // merge): hashed, and still every neighbour exactly once.
    for (const Vec3 extent : {Vec3(1e4f, 1e4f, 1e4f), Vec3(3e6f, 10.0f, 10.0f), Vec3(1e5f, 1e5f, 1.0f)}) {
        Particles p = random_particles(600, 41, extent);
        for (size_t i = 0; i + 1 < p.size(); i += 2) p.position[i + 1] = p.position[i] + Vec3(0.6f, -0.3f, 0.9f);
        EXPECT_EQ(check_against_brute_force(p, 1.0f), NeighborGrid::Layout::Hashed);
    }
    // Compact: dense.
    EXPECT_EQ(check_against_brute_force(random_particles(2000, 3, Vec3(20, 5, 20)), 1.0f), NeighborGrid::Layout::Dense);
}

TEST(NeighborGrid, BlockedLayoutRelabelsAndRebuildsToTheSameCells) {
    Particles p = random_particles(3000, 7, Vec3(300, 4, 300), 0.0f);
    NeighborGrid g;
    g.build(p.position, p.active, 1.0f);
    ASSERT_EQ(g.layout(), NeighborGrid::Layout::Blocked);
    // Permute as the solver does, relabel, and rebuild: the same runs, now in identity order.
    const std::vector<uint32_t> order(g.order().begin(), g.order().end());
    std::vector<uint32_t> buckets;
    for (uint32_t i : order) buckets.push_back(g.bucket_of(i));
    Particles q = p;
    for (size_t k = 0; k < order.size(); ++k) q.position[k] = p.position[order[k]];
    g.relabel_identity();
    for (size_t k = 0; k < order.size(); ++k) {
        ASSERT_EQ(g.order()[k], k);
        ASSERT_EQ(g.bucket_of(uint32_t(k)), buckets[k]);
    }
    NeighborGrid h;
    h.build(q.position, q.active, 1.0f);
    for (size_t k = 0; k < order.size(); ++k) {
        ASSERT_EQ(h.order()[k], k) << "a sorted cloud sorts to itself";
        ASSERT_EQ(h.bucket_of(uint32_t(k)), buckets[k]);
    }
    EXPECT_EQ(check_against_brute_force(q, 1.0f), NeighborGrid::Layout::Blocked);
}

TEST(NeighborGrid, GridSpringForcesEqualThePaperPairLoop) {
    for (uint32_t seed : {1u, 2u, 3u}) {
        for (float spread : {3.0f, 12.0f, 120.0f, 400.0f}) {  // dense, dense, blocked, hashed
            Particles a = random_particles(700, seed, Vec3(spread, spread * 0.3f, spread));
            Particles b = a;
            SpringDef def{.stiffness = 20.0f, .min_distance = 1.0f, .max_distance = 0.7f, .mode = SpringMode::Grid};
            add_spring_forces_pairs(a, def);
            NeighborGrid g;
            g.build(b.position, b.active, spring_reach(def));
            add_spring_forces_grid(b, g, def);
            size_t nonzero = 0;
            for (size_t i = 0; i < a.size(); ++i) {
                nonzero += glm::length(a.force[i]) > 0.0f;
                // Same terms summed in a different order: float rounding of up to ~50
                // terms of magnitude <= k r, relative 1e-5 of the term scale.
                ASSERT_NEAR(a.force[i].x, b.force[i].x, 1e-4f * 20.0f) << i;
                ASSERT_NEAR(a.force[i].y, b.force[i].y, 1e-4f * 20.0f) << i;
                ASSERT_NEAR(a.force[i].z, b.force[i].z, 1e-4f * 20.0f) << i;
            }
            if (spread < 100.0f) {
                EXPECT_GT(nonzero, 100u) << "the case must exercise springs";
            }
        }
    }
}

TEST(NeighborLists, HoldExactlyTheBruteForcePairsWithinReachInRangeOrder) {
    for (float spread : {4.0f, 12.0f, 150.0f, 3000.0f}) {  // dense, dense, blocked, hashed
        Particles p = random_particles(1500, 11, Vec3(spread, spread * 0.3f, spread));
        NeighborGrid g;
        g.build(p.position, p.active, 1.0f);
        // Relabel as the solver does: binned particle k at index k.
        const std::vector<uint32_t> order(g.order().begin(), g.order().end());
        std::vector<Vec3> x(order.size());
        for (size_t k = 0; k < order.size(); ++k) x[k] = p.position[order[k]];
        g.relabel_identity();
        // Both builds (AVX2 where the CPU has it, and the scalar loops); the densest case
        // lists more than the AVX2 build's 256-entry buffer holds.
        for (int c = 0; c < 4; ++c) {
            const float reach = c % 2 == 0 ? 1.0f : 0.6f;
            NeighborLists lists;
            lists.set_simd(c < 2);
            lists.build(g, x, reach);
            ASSERT_EQ(lists.size(), x.size());
            size_t pairs = 0, longest = 0;
            for (uint32_t i = 0; i < x.size(); ++i) {
                std::vector<uint32_t> want;
                for (uint32_t j = 0; j < x.size(); ++j)
                    if (glm::dot(x[i] - x[j], x[i] - x[j]) < reach * reach) want.push_back(j);
                const auto l = lists.of(i);
                std::vector<uint32_t> got(l.begin(), l.end());
                // The same set; the list keeps the 27-cell ranges' order, so sort to compare.
                std::vector<uint32_t> sorted = got;
                std::sort(sorted.begin(), sorted.end());
                ASSERT_EQ(sorted, want) << "spread " << spread << " case " << c << " particle " << i;
                // ... and that order is the ranges' order: the candidate loop, filtered.
                std::vector<uint32_t> ranged;
                size_t run = 0;
                while (g.run_start(run + 1) <= i) ++run;
                g.for_each_neighbor_range(run, [&](uint32_t s, uint32_t e) {
                    for (uint32_t j = s; j < e; ++j)
                        if (glm::dot(x[i] - x[j], x[i] - x[j]) < reach * reach) ranged.push_back(j);
                });
                ASSERT_EQ(got, ranged);
                pairs += got.size();
                longest = std::max(longest, got.size());
            }
            EXPECT_EQ(lists.entries(), pairs);
            if (spread < 5.0f && reach == 1.0f) {
                EXPECT_GT(longest, 256u) << "a list must outgrow the AVX2 build's buffer";
            }
            if (spread < 20.0f) {
                EXPECT_GT(pairs, 3 * x.size()) << "the case must have neighbours";
            }
        }
    }
}

TEST(NeighborLists, StaleOnceAParticleHasMovedNearlyHalfTheSkin) {
    Particles p = random_particles(800, 5, Vec3(6, 2, 6), 0.0f);
    NeighborGrid g;
    g.build(p.position, p.active, 1.0f);
    std::vector<Vec3> x(g.order().size());
    for (size_t k = 0; k < x.size(); ++k) x[k] = p.position[g.order()[k]];
    g.relabel_identity();
    NeighborLists lists;
    const float skin = 0.2f;
    lists.build(g, x, 1.0f + skin);
    EXPECT_EQ(lists.builds(), 1u);
    EXPECT_FALSE(lists.stale(x, skin));
    std::vector<Vec3> y = x;
    y[417].x += 0.4f * skin;  // under the 0.45 skin limit: every pair within 1 m is still listed
    EXPECT_FALSE(lists.stale(y, skin));
    y[417].x += 0.1f * skin;
    EXPECT_TRUE(lists.stale(y, skin));
    y = x;
    y[3].z = std::nanf("");
    EXPECT_TRUE(lists.stale(y, skin)) << "a NaN position must force a rebuild";
}

}  // namespace
}  // namespace mr
