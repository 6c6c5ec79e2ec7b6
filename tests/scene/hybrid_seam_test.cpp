// One surface where the hybrid's grid and particles meet (issue 46's seam): at the foot of the
// waterfall the grid's water becomes a term of the metaball field near the particles
// (join_heightfield_to_field), the heightfield mesh leaves those cells out, and the two meet
// at the water's level along the border: no gap, no step, no hole.
#include <metariver/scene.h>
#include <metariver/sparse_field.h>
#include <metariver/surface.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace mr {
namespace {

/// Heights at which the mesh's triangles [first, last) cross the vertical line through (x, z).
std::vector<float> crossings(const SurfaceMesh& m, size_t first, size_t last, float x, float z) {
    std::vector<float> ys;
    for (size_t t = first; t < last; ++t) {
        const Vec3& a = m.positions[m.indices[3 * t]];
        const Vec3& b = m.positions[m.indices[3 * t + 1]];
        const Vec3& c = m.positions[m.indices[3 * t + 2]];
        const float d = (b.x - a.x) * (c.z - a.z) - (c.x - a.x) * (b.z - a.z);
        if (std::abs(d) < 1e-12f) continue;
        const float u = ((x - a.x) * (c.z - a.z) - (c.x - a.x) * (z - a.z)) / d;
        const float v = ((b.x - a.x) * (z - a.z) - (x - a.x) * (b.z - a.z)) / d;
        if (u < -1e-5f || v < -1e-5f || u + v > 1.0f + 1e-5f) continue;
        ys.push_back(a.y + u * (b.y - a.y) + v * (c.y - a.y));
    }
    return ys;
}

TEST(HybridSeam, TheGridsWaterAndTheMetaballsMeetInOneSurfaceAtTheFoot) {
    SceneDef d = preset("waterfall").value();
    d.surface = false;
    auto sim = Simulation::create(d);
    ASSERT_TRUE(sim.ok()) << sim.error().message;
    Simulation& s = *sim.value();
    for (int f = 0; f < 360; ++f) s.step(1.0f / 60.0f);  // 6 s: the sheet falls into a pool
    const HeightfieldWater& w = *s.heightfield();
    const std::span<const Vec3> bed = s.terrain().vertices();
    const size_t cols = size_t(w.columns);
    std::vector<Vec3> balls;
    s.particles().gather_active_positions(balls);
    ASSERT_GT(balls.size(), 50u);
    SparseFieldDef fd;
    fd.kernel = poly6_kernel(d.field.radius, 1.0f);
    fd.resolution = d.field.resolution;
    fd.bounds_offset = d.field.bounds_offset;
    SparseField field;
    ASSERT_TRUE(field.build(balls, fd).ok());
    SurfaceWorkspace ws;
    const float threshold = d.field.threshold;

    // Before: the metaballs alone reach under the pool's surface (they overlap it).
    SurfaceMesh before;
    extract_surface_sparse(field, threshold, before, ws);
    HeightfieldSeam seam;
    join_heightfield_to_field(bed, w.depth, w.rows, w.columns, threshold, d.field.radius / 3.0f, field, seam);
    ASSERT_GT(seam.columns, 200u) << "the field takes the grid's water where the balls reach it, around the foot";
    const SampleGrid& g = field.grid();
    // The cells holding a column with the term (where the balls reach the water).
    std::vector<uint8_t> touched(seam.cell.size(), 0);
    for (int k = 0; k < g.nz; ++k)
        for (int i = 0; i < g.nx; ++i) {
            if (!seam.column[size_t(i) + size_t(g.nx) * size_t(k)]) continue;
            const Vec3 p = g.position(i, 0, k);
            const int cj = int(std::floor(p.x - bed[0].x)), ci = int(std::floor(p.z - bed[0].z));
            if (ci >= 0 && cj >= 0 && ci + 1 < w.rows && cj + 1 < w.columns) touched[size_t(ci) * (cols - 1) + size_t(cj)] = 1;
        }
    const auto level = [&](size_t k) { return bed[k].y + w.depth[k]; };
    float overlap = 0.0f;
    for (size_t c = 0; c < seam.cell.size(); ++c) {
        if (!touched[c]) continue;
        const size_t k = (c / (cols - 1)) * cols + c % (cols - 1);
        const float x = 0.5f * (bed[k].x + bed[k + 1].x), z = 0.5f * (bed[k].z + bed[k + cols].z);
        const float s_mid = 0.5f * (level(k + 1) + level(k + cols));  // on the cell's diagonal
        for (const float y : crossings(before, 0, before.triangle_count(), x, z)) overlap = std::max(overlap, s_mid - y);
    }

    // After: the field with the grid's term, then the heightfield without the field's cells.
    SurfaceMesh joined;
    extract_surface_sparse(field, threshold, joined, ws);
    const size_t field_triangles = joined.triangle_count(), field_vertices = joined.vertex_count();
    append_heightfield_surface(bed, w.depth, w.rows, w.columns, joined, nullptr, {}, nullptr, seam.cell);
    // Where the field's surface ends (its vertices beside a block it does not store) over
    // the grid's water, it ends at the water's level: how far above it (a step) at most.
    // Beside a sample the field does not store (the balls add nothing there). Beside the
    // columns without the term the field's water lies under the heightfield, which is drawn
    // there (no cell of theirs is left out), and balls' own surfaces pass: not counted.
    const auto absent = [&](int i, int j, int k) {
        if (i < 0 || j < 0 || k < 0 || i >= g.nx || j >= g.ny || k >= g.nz) return true;
        constexpr int B = SparseField::kBlock;
        return field.slot(i / B, j / B, k / B) == SparseField::kNoBlock;
    };

    size_t edge = 0;
    float step = 0.0f;
    for (size_t v = 0; v < joined.vertex_count() && v < field_vertices; ++v) {
        const Vec3 p = joined.positions[v];
        const int i = int(std::floor((p.x - g.origin.x) / g.spacing)), j = int(std::floor((p.y - g.origin.y) / g.spacing)),
                  k = int(std::floor((p.z - g.origin.z) / g.spacing));
        bool beside = false;
        for (int a = i; a <= i + 1; ++a)  // the corners of the marching cubes cell it lies in
            for (int b = j; b <= j + 1; ++b)
                for (int c = k; c <= k + 1; ++c) beside = beside || absent(a, b, c);
        if (!beside) continue;
        // The grid's highest level around it (the cells its marching cubes cell touches, all wet).
        float s_here = -std::numeric_limits<float>::max();
        bool wet = true;
        for (const float ex : {-g.spacing, g.spacing})
            for (const float ez : {-g.spacing, g.spacing}) {
                const int cj = int(std::floor(p.x + ex - bed[0].x)), ci = int(std::floor(p.z + ez - bed[0].z));
                if (ci < 0 || cj < 0 || ci + 1 >= w.rows || cj + 1 >= w.columns) {
                    wet = false;
                    continue;
                }
                const size_t q = size_t(ci) * cols + size_t(cj);
                for (const size_t r : {q, q + 1, q + cols, q + cols + 1}) {
                    wet = wet && w.depth[r] > 0.005f;
                    s_here = std::max(s_here, level(r));
                }
            }
        if (!wet) continue;
        if (p.y < s_here - 0.3f || p.y > s_here + 1.5f) continue;  // the water's, not a drop's high above
        ++edge;
        step = std::max(step, p.y - s_here);
    }
    // Over the field's cells the top of the water is the grid's level or the metaballs over it.
    float hole = 0.0f;
    for (size_t c = 0; c < seam.cell.size(); ++c) {
        if (!seam.cell[c]) continue;
        const size_t k = (c / (cols - 1)) * cols + c % (cols - 1);
        const float x = 0.5f * (bed[k].x + bed[k + 1].x), z = 0.5f * (bed[k].z + bed[k + cols].z);
        const float s_mid = 0.5f * (level(k + 1) + level(k + cols));
        float top = -std::numeric_limits<float>::max();
        for (const float y : crossings(joined, 0, field_triangles, x, z)) top = std::max(top, y);
        hole = std::max(hole, s_mid - top);
    }
    std::printf("seam at 6 s: %zu particles, %zu cells drawn by the field; before: the metaballs reach %.3f m under "
                "the pool's surface; after: the field's surface ends over the water (%zu vertices) at most %.4f m above "
                "its level, and where it draws the pool its top is at most %.4f m under the level\n",
                balls.size(), seam.cells, overlap, edge, step, hole);
    // The flow detail: the field's flat water takes the grid's velocity as the heightfield's
    // vertices carry it. At the heightfield mesh's own wet vertices (5 mm lower, where the
    // field's water lies) seam_grid_velocities gives their velocity with the grid's share 1,
    // so the two meet without a jump in the flow's streaks; over the drops it falls to 0.
    SurfaceMesh hf;
    std::vector<Vec3> hf_velocity;
    append_heightfield_surface(bed, w.depth, w.rows, w.columns, hf, nullptr, w.velocity, &hf_velocity);
    std::vector<Vec3> probe;
    std::vector<size_t> probe_of;
    for (size_t v = 0; v < hf.vertex_count(); ++v) {
        const Vec3 p = hf.positions[v];
        const int cj = std::min(int(std::floor(p.x - bed[0].x)), w.columns - 2), ci = std::min(int(std::floor(p.z - bed[0].z)), w.rows - 2);
        if (ci < 0 || cj < 0) continue;
        const size_t q = size_t(ci) * cols + size_t(cj);
        if (!(w.depth[q] > 0.005f && w.depth[q + 1] > 0.005f && w.depth[q + cols] > 0.005f && w.depth[q + cols + 1] > 0.005f))
            continue;  // a fully wet cell's (the field's term is defined there)
        probe.push_back(p - Vec3(0.0f, 0.005f, 0.0f));
        probe_of.push_back(v);
    }
    ASSERT_GT(probe.size(), 300u);
    std::vector<glm::vec4> grid_part;
    seam_grid_velocities(bed, w.depth, w.velocity, w.rows, w.columns, d.field.radius / 3.0f, probe, grid_part);
    float jump = 0.0f, fastest = 0.0f, least_share = 1.0f;
    for (size_t n = 0; n < probe.size(); ++n) {
        jump = std::max(jump, glm::length(Vec3(grid_part[n]) - hf_velocity[probe_of[n]]));
        fastest = std::max(fastest, glm::length(hf_velocity[probe_of[n]]));
        least_share = std::min(least_share, grid_part[n].w);
    }
    std::vector<glm::vec4> high;
    const std::vector<Vec3> above = {probe[0] + Vec3(0.0f, d.field.radius / 3.0f + 0.01f, 0.0f)};
    seam_grid_velocities(bed, w.depth, w.velocity, w.rows, w.columns, d.field.radius / 3.0f, above, high);
    std::printf("flow at the seam: %zu wet heightfield vertices (up to %.2f m/s): the grid's part differs by at most "
                "%.2e m/s, share at least %.3f; a skirt's width over the water: share %.3f\n",
                probe.size(), fastest, jump, least_share, high[0].w);
    EXPECT_GT(fastest, 0.5f);  // the pool flows: the check can see a jump
    EXPECT_LT(jump, 1e-4f);
    EXPECT_GT(least_share, 0.999f);
    EXPECT_EQ(high[0].w, 0.0f);

    EXPECT_GT(overlap, 0.05f);  // what the join removes: the metaballs poked into the pool
    EXPECT_GE(edge, 5u);
    EXPECT_LT(step, 0.05f);  // no step where the field's surface hands over to the heightfield
    EXPECT_LT(hole, 0.01f);  // and no hole where it draws the pool
}

}  // namespace
}  // namespace mr
