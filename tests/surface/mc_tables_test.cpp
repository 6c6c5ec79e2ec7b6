// Tests for the marching-cubes tables (Bourke's numbering): every one of the 256 cases
// is checked against corner states computed from the cube's geometry.
#include <metariver/surface.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <utility>
#include <vector>

namespace mr {
namespace {

using Tri = std::array<int, 3>;
using Segment = std::pair<int, int>;  // directed: from cube edge .first to cube edge .second

bool inside(int cube, int corner) { return ((cube >> corner) & 1) != 0; }

glm::vec3 corner_pos(int c) {
    const auto& o = mc::kCornerOffset[c];
    return glm::vec3(float(o[0]), float(o[1]), float(o[2]));
}

glm::vec3 edge_mid(int e) {
    return 0.5f * (corner_pos(mc::kEdgeCorners[e][0]) + corner_pos(mc::kEdgeCorners[e][1]));
}

// Active edges of a case from the cube's geometry: corner pairs one unit apart whose
// states differ, named through kEdgeCorners.
uint16_t active_edges(int cube) {
    uint16_t mask = 0;
    for (int e = 0; e < 12; ++e) {
        if (inside(cube, mc::kEdgeCorners[e][0]) != inside(cube, mc::kEdgeCorners[e][1])) mask |= uint16_t(1u << e);
    }
    return mask;
}

std::vector<Tri> triangles(int cube) {
    std::vector<Tri> tris;
    const auto& row = mc::kTriTable[cube];
    for (int t = 0; t + 2 < 16 && row[t] >= 0; t += 3) tris.push_back({row[t], row[t + 1], row[t + 2]});
    return tris;
}

// The sum over a triangle's three cube edges of the edge's inside-to-outside direction:
// where the triangle's normal must point.
glm::vec3 inside_to_outside(int cube, const Tri& t) {
    glm::vec3 dir(0.0f);
    for (int e : t) {
        const glm::vec3 a = corner_pos(mc::kEdgeCorners[e][0]), b = corner_pos(mc::kEdgeCorners[e][1]);
        dir += inside(cube, mc::kEdgeCorners[e][0]) ? b - a : a - b;
    }
    return dir;
}

// Faces as (axis, side); an edge lies on the face when both its corners do.
bool edge_on_face(int e, int axis, int side) {
    return mc::kCornerOffset[mc::kEdgeCorners[e][0]][axis] == side &&
           mc::kCornerOffset[mc::kEdgeCorners[e][1]][axis] == side;
}

bool edges_share_face(int e1, int e2) {
    for (int axis = 0; axis < 3; ++axis) {
        for (int side = 0; side < 2; ++side) {
            if (edge_on_face(e1, axis, side) && edge_on_face(e2, axis, side)) return true;
        }
    }
    return false;
}

// Triangle sides used once in a case: the case surface's boundary.
std::vector<Segment> boundary_segments(int cube) {
    std::map<Segment, int> directed;
    for (const Tri& t : triangles(cube)) {
        for (int s = 0; s < 3; ++s) ++directed[{t[s], t[(s + 1) % 3]}];
    }
    std::vector<Segment> out;
    for (const auto& [seg, n] : directed) {
        const int undirected = n + (directed.count({seg.second, seg.first}) ? directed.at({seg.second, seg.first}) : 0);
        if (undirected == 1) out.push_back(seg);
    }
    return out;
}

TEST(McTables, CornerOffsetsAreBourkes) {
    // The header's table: 0 (0,0,0) 1 (1,0,0) 2 (1,0,1) 3 (0,0,1) 4 (0,1,0) 5 (1,1,0) 6 (1,1,1) 7 (0,1,1).
    const std::array<std::array<int, 3>, 8> expected = {
        {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, {0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1}}};
    EXPECT_EQ(mc::kCornerOffset, expected);
    std::set<std::array<int, 3>> distinct(mc::kCornerOffset.begin(), mc::kCornerOffset.end());
    EXPECT_EQ(distinct.size(), 8u);
}

TEST(McTables, EdgeCornersAreBourkesAndCoverTheCube) {
    // Bourke: edges 0-3 go round the bottom (corners 0-3), 4-7 the top, 8-11 join them.
    const std::array<std::array<int, 2>, 12> expected = {{{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6},
                                                          {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}}};
    EXPECT_EQ(mc::kEdgeCorners, expected);
    std::set<std::pair<int, int>> distinct;
    for (const auto& e : mc::kEdgeCorners) {
        const auto& a = mc::kCornerOffset[e[0]];
        const auto& b = mc::kCornerOffset[e[1]];
        const int differing = (a[0] != b[0]) + (a[1] != b[1]) + (a[2] != b[2]);
        EXPECT_EQ(differing, 1) << "edge " << e[0] << "-" << e[1] << " is not a cube edge";
        distinct.insert({std::min(e[0], e[1]), std::max(e[0], e[1])});
    }
    EXPECT_EQ(distinct.size(), 12u);
}

TEST(McTables, EdgeTableMatchesCornerStates) {
    for (int cube = 0; cube < 256; ++cube) {
        EXPECT_EQ(mc::kEdgeTable[cube], active_edges(cube)) << "case " << cube;
        EXPECT_EQ(mc::kEdgeTable[cube], mc::kEdgeTable[255 - cube]) << "complement of case " << cube;
    }
    // Bourke's published first row.
    const std::array<uint16_t, 16> bourke = {0x0,   0x109, 0x203, 0x30a, 0x406, 0x50f, 0x605, 0x70c,
                                             0x80c, 0x905, 0xa0f, 0xb06, 0xc0a, 0xd03, 0xe09, 0xf00};
    for (int cube = 0; cube < 16; ++cube) EXPECT_EQ(mc::kEdgeTable[cube], bourke[cube]) << "case " << cube;
}

TEST(McTables, TriTableRowsAreWellFormed) {
    for (int cube = 0; cube < 256; ++cube) {
        const auto& row = mc::kTriTable[cube];
        int n = 0;
        while (n < 16 && row[n] >= 0) ++n;
        ASSERT_LT(n, 16) << "case " << cube << " is not -1 terminated";
        EXPECT_EQ(n % 3, 0) << "case " << cube;
        for (int t = n; t < 16; ++t) EXPECT_EQ(row[t], -1) << "case " << cube << " entry " << t;

        const uint16_t active = active_edges(cube);
        uint16_t used = 0;
        for (const Tri& t : triangles(cube)) {
            EXPECT_TRUE(t[0] != t[1] && t[1] != t[2] && t[2] != t[0]) << "case " << cube;
            for (int e : t) {
                ASSERT_TRUE(e >= 0 && e < 12) << "case " << cube;
                EXPECT_TRUE(active & (1u << e)) << "case " << cube << " uses inactive edge " << e;
                used = uint16_t(used | (1u << e));
            }
        }
        EXPECT_EQ(used, active) << "case " << cube << ": an active edge has no triangle";
    }
    EXPECT_TRUE(triangles(0).empty());
    EXPECT_TRUE(triangles(255).empty());
}

TEST(McTables, CaseSurfacesAreManifoldWithBoundaryOnTheCubeFaces) {
    for (int cube = 1; cube < 255; ++cube) {
        std::map<Segment, int> directed;
        for (const Tri& t : triangles(cube)) {
            for (int s = 0; s < 3; ++s) ++directed[{t[s], t[(s + 1) % 3]}];
        }
        for (const auto& [seg, n] : directed) {
            EXPECT_EQ(n, 1) << "case " << cube << ": side " << seg.first << "->" << seg.second << " repeated";
            const auto rev = directed.find({seg.second, seg.first});
            const int uses = n + (rev != directed.end() ? rev->second : 0);
            EXPECT_LE(uses, 2) << "case " << cube;
            // Open sides lie on a cube face; shared sides cross the interior (a shared
            // side in a face would meet the neighbouring cell's triangles there).
            EXPECT_EQ(uses == 1, edges_share_face(seg.first, seg.second))
                << "case " << cube << ": side " << seg.first << "->" << seg.second << " used " << uses << " times";
        }
        // On each face, the open sides pair up the face's crossed edges exactly once.
        for (int axis = 0; axis < 3; ++axis) {
            for (int side = 0; side < 2; ++side) {
                std::map<int, int> touched;
                for (const Segment& s : boundary_segments(cube)) {
                    if (edge_on_face(s.first, axis, side) && edge_on_face(s.second, axis, side)) {
                        ++touched[s.first];
                        ++touched[s.second];
                    }
                }
                for (int e = 0; e < 12; ++e) {
                    if (!edge_on_face(e, axis, side)) continue;
                    const int expected = (active_edges(cube) >> e) & 1;
                    EXPECT_EQ(touched[e], expected)
                        << "case " << cube << " face " << axis << "/" << side << " edge " << e;
                }
            }
        }
    }
}

// Crack-free and consistently oriented across cells: the contour a case leaves on a face
// depends only on that face's four corners, and the opposite face of the neighbouring
// cell (same four samples) gets the same contour traversed the other way.
TEST(McTables, FaceContoursDependOnlyOnTheFaceAndMatchTheNeighbour) {
    for (int axis = 0; axis < 3; ++axis) {
        const int u = (axis + 1) % 3, v = (axis + 2) % 3;
        // Face-local name of a face edge: the set of its corners' (u, v) positions.
        const auto local = [&](int e) {
            const auto& a = mc::kCornerOffset[mc::kEdgeCorners[e][0]];
            const auto& b = mc::kCornerOffset[mc::kEdgeCorners[e][1]];
            const int pa = a[u] + 2 * a[v], pb = b[u] + 2 * b[v];
            return std::min(pa, pb) * 4 + std::max(pa, pb);
        };
        // contours[side][face state] = directed local segments; -1 entries unset yet.
        std::map<int, std::set<std::pair<int, int>>> contours[2];
        for (int side = 0; side < 2; ++side) {
            for (int cube = 0; cube < 256; ++cube) {
                int face_state = 0;
                for (int c = 0; c < 8; ++c) {
                    const auto& o = mc::kCornerOffset[c];
                    if (o[axis] == side && inside(cube, c)) face_state |= 1 << (o[u] + 2 * o[v]);
                }
                std::set<std::pair<int, int>> segs;
                for (const Segment& s : boundary_segments(cube)) {
                    if (edge_on_face(s.first, axis, side) && edge_on_face(s.second, axis, side)) {
                        segs.insert({local(s.first), local(s.second)});
                    }
                }
                const auto [it, fresh] = contours[side].emplace(face_state, segs);
                if (!fresh) {
                    EXPECT_EQ(it->second, segs) << "axis " << axis << " side " << side << " face state " << face_state
                                                << ": case " << cube << " disagrees with another case";
                }
            }
        }
        for (int state = 0; state < 16; ++state) {
            std::set<std::pair<int, int>> reversed;
            for (const auto& s : contours[0][state]) reversed.insert({s.second, s.first});
            EXPECT_EQ(contours[1][state], reversed) << "axis " << axis << " face state " << state;
        }
    }
}

// Triangles face from the inside corners toward the outside ones (vertices at edge
// midpoints). Per triangle: the normal has positive dot with the sum, over the three
// edges it cuts, of the inside-to-outside edge direction. Per case: the summed normal
// has positive dot with (outside corners' centroid - inside corners' centroid).
TEST(McTables, TrianglesFaceFromInsideToOutside) {
    for (int cube = 1; cube < 255; ++cube) {
        glm::vec3 in(0.0f), out(0.0f);
        int n_in = 0, n_out = 0;
        for (int c = 0; c < 8; ++c) {
            if (inside(cube, c)) {
                in += corner_pos(c);
                ++n_in;
            } else {
                out += corner_pos(c);
                ++n_out;
            }
        }
        const glm::vec3 case_dir = out / float(n_out) - in / float(n_in);
        float sum = 0.0f;
        for (const Tri& t : triangles(cube)) {
            const glm::vec3 a = edge_mid(t[0]), b = edge_mid(t[1]), c = edge_mid(t[2]);
            const glm::vec3 normal = glm::cross(b - a, c - a);
            sum += glm::dot(normal, case_dir);
            EXPECT_GT(glm::dot(normal, inside_to_outside(cube, t)), 0.0f)
                << "case " << cube << " triangle " << t[0] << "," << t[1] << "," << t[2];
        }
        // Checkerboard-like cases have inside and outside centroids that coincide.
        if (glm::length(case_dir) > 1e-6f) {
            EXPECT_GT(sum, 0.0f) << "case " << cube;
        }
    }
}

TEST(McTables, ComplementaryCasesMirrorEachOther) {
    for (int cube = 1; cube < 255; ++cube) {
        const int comp = 255 - cube;
        bool ambiguous = false;  // some face with two diagonal corners inside and two outside
        for (int axis = 0; axis < 3; ++axis) {
            for (int side = 0; side < 2; ++side) {
                int state[2][2] = {};
                for (int c = 0; c < 8; ++c) {
                    const auto& o = mc::kCornerOffset[c];
                    if (o[axis] == side) state[o[(axis + 1) % 3]][o[(axis + 2) % 3]] = inside(cube, c);
                }
                const bool diagonal = state[0][0] == state[1][1] && state[0][1] == state[1][0];
                if (diagonal && state[0][0] != state[0][1]) ambiguous = true;
            }
        }
        std::vector<Segment> a = boundary_segments(cube), b = boundary_segments(comp);
        if (ambiguous) {
            // The complement joins what the case kept apart: the contour must differ.
            std::set<Segment> undirected_a, undirected_b;
            for (auto s : a) undirected_a.insert({std::min(s.first, s.second), std::max(s.first, s.second)});
            for (auto s : b) undirected_b.insert({std::min(s.first, s.second), std::max(s.first, s.second)});
            EXPECT_NE(undirected_a, undirected_b) << "case " << cube;
            continue;
        }
        // Unambiguous: the same contour, traversed the other way, and as many triangles.
        for (auto& s : b) std::swap(s.first, s.second);
        std::sort(a.begin(), a.end());
        std::sort(b.begin(), b.end());
        EXPECT_EQ(a, b) << "case " << cube;
        EXPECT_EQ(triangles(cube).size(), triangles(comp).size()) << "case " << cube;
    }
}

// Each case through extract_surface on a single 2x2x2 grid.
TEST(McTables, SingleCubeExtractionMatchesEveryCase) {
    Lcg rng(7u);
    for (int variant = 0; variant < 3; ++variant) {
        for (int cube = 0; cube < 256; ++cube) {
            ScalarGrid grid;
            grid.reset(2, 2, 2, Vec3(0.0f), 1.0f);
            const float threshold = 0.5f;
            for (int c = 0; c < 8; ++c) {
                const auto& o = mc::kCornerOffset[c];
                float value = inside(cube, c) ? 1.0f : 0.0f;
                if (variant > 0) value = inside(cube, c) ? rng.uniform(0.51f, 3.0f) : rng.uniform(-2.0f, 0.49f);
                grid.values[grid.index(o[0], o[1], o[2])] = value;
            }
            SurfaceMesh mesh;
            extract_surface(grid, threshold, mesh);
            const uint16_t active = active_edges(cube);
            ASSERT_EQ(mesh.vertex_count(), size_t(__builtin_popcount(active))) << "case " << cube;
            ASSERT_EQ(mesh.triangle_count(), triangles(cube).size()) << "case " << cube;

            // Which cube edge each vertex lies on, found from its position alone.
            std::vector<int> vertex_edge(mesh.vertex_count(), -1);
            uint16_t seen = 0;
            for (size_t vi = 0; vi < mesh.vertex_count(); ++vi) {
                const Vec3 p = mesh.positions[vi];
                for (int e = 0; e < 12; ++e) {
                    const Vec3 a = corner_pos(mc::kEdgeCorners[e][0]), b = corner_pos(mc::kEdgeCorners[e][1]);
                    const Vec3 d = b - a;
                    const float t = glm::dot(p - a, d);
                    // On the edge's line: the two fixed coordinates are copied exactly.
                    if (t > 0.0f && t < 1.0f && glm::length(p - (a + t * d)) < 1e-6f) {
                        vertex_edge[vi] = e;
                        // The edge's linear interpolant equals the threshold at the vertex.
                        const float fa = grid.values[grid.index(int(a.x), int(a.y), int(a.z))];
                        const float fb = grid.values[grid.index(int(b.x), int(b.y), int(b.z))];
                        EXPECT_NEAR(fa + t * (fb - fa), threshold, 1e-5f) << "case " << cube;  // float rounding of t
                    }
                }
                ASSERT_GE(vertex_edge[vi], 0) << "case " << cube << " vertex off the cube edges";
                EXPECT_FALSE(seen & (1u << vertex_edge[vi])) << "case " << cube << ": two vertices on one edge";
                seen = uint16_t(seen | (1u << vertex_edge[vi]));
                EXPECT_NEAR(glm::length(mesh.normals[vi]), 1.0f, 1e-5f);  // float normalisation
            }
            EXPECT_EQ(seen, active) << "case " << cube;

            // The mesh's triangles are the table's, vertex by vertex.
            const std::vector<Tri> expected = triangles(cube);
            for (size_t t = 0; t < mesh.triangle_count(); ++t) {
                for (int s = 0; s < 3; ++s) {
                    EXPECT_EQ(vertex_edge[mesh.indices[3 * t + s]], expected[t][s]) << "case " << cube;
                }
                // Orientation with real vertex positions: the normal leaves the inside corners.
                const Vec3 a = mesh.positions[mesh.indices[3 * t]], b = mesh.positions[mesh.indices[3 * t + 1]],
                           c = mesh.positions[mesh.indices[3 * t + 2]];
                EXPECT_GT(glm::dot(glm::cross(b - a, c - a), inside_to_outside(cube, expected[t])), 0.0f)
                    << "case " << cube << " variant " << variant;
            }
        }
    }
}

}  // namespace
}  // namespace mr
