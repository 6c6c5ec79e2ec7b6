// metariver surface: marching-cubes tables in Paul Bourke's numbering.
//
// Paul Bourke, "Polygonising a scalar field" (1994), http://paulbourke.net/geometry/polygonise/
// gives the corner and edge numbering used here and the 256-entry edge and triangle
// tables. kCornerOffset, kEdgeCorners and kEdgeTable are Bourke's. kTriTable is
// generated at compile time from the same numbering instead of being transcribed: for
// each case the iso-contour is traced over the six cube faces and each closed contour
// is fan-triangulated from a vertex whose diagonals all cross the cube's interior (a
// diagonal lying in a face could meet the neighbouring cell's triangles). Two choices are pinned so that neighbouring cells always agree
// (the mesh is watertight) and the winding is ours:
//   * On an ambiguous face (two diagonal corners inside, two outside) the inside corners
//     are kept apart and the outside corners joined. The contour on a face therefore
//     depends only on that face's four corners, so two cells sharing a face emit the
//     same contour segments (no cracks).
//   * Triangles are counter-clockwise seen from outside (the side below the threshold),
//     for a cube index whose bit c is set when corner c is INSIDE (value > threshold).
//     Bourke indexes by corners below the iso level; with his edgeTable that is the
//     same table, since the edge mask of a case equals that of its complement.
// A case with E crossed edges and C contours gets E - 2C triangles (at most 5).
// mc_tables_test proves the properties above for all 256 cases.
#include <metariver/surface.h>

#include <stdexcept>

namespace mr::mc {

namespace {

constexpr std::array<std::array<int, 3>, 8> kCorners = {{
    {0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}, {0, 1, 0}, {1, 1, 0}, {1, 1, 1}, {0, 1, 1},
}};

constexpr std::array<std::array<int, 2>, 12> kEdges = {{
    {0, 1}, {1, 2}, {2, 3}, {3, 0},  // the y = 0 face
    {4, 5}, {5, 6}, {6, 7}, {7, 4},  // the y = 1 face
    {0, 4}, {1, 5}, {2, 6}, {3, 7},  // the four edges along y
}};

constexpr int corner_at(int x, int y, int z) {
    for (int c = 0; c < 8; ++c) {
        if (kCorners[c][0] == x && kCorners[c][1] == y && kCorners[c][2] == z) return c;
    }
    throw std::logic_error("no such corner");
}

constexpr int edge_between(int a, int b) {
    for (int e = 0; e < 12; ++e) {
        if ((kEdges[e][0] == a && kEdges[e][1] == b) || (kEdges[e][0] == b && kEdges[e][1] == a)) return e;
    }
    throw std::logic_error("corners not joined by an edge");
}

/// A cube face: its corners counter-clockwise seen from outside the cube, and
/// edges[k] joining corners[k] and corners[(k + 1) % 4].
struct Face {
    std::array<int, 4> corners{};
    std::array<int, 4> edges{};
};

constexpr std::array<Face, 6> make_faces() {
    std::array<Face, 6> faces{};
    int f = 0;
    for (int axis = 0; axis < 3; ++axis) {
        // (u, v) = the next two axes cyclically, so u x v points along +axis.
        const int u = (axis + 1) % 3;
        const int v = (axis + 2) % 3;
        for (int side = 0; side < 2; ++side) {
            // Counter-clockwise about the outward normal: +axis on side 1, -axis on side 0.
            constexpr std::array<std::array<int, 2>, 4> ccw = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
            constexpr std::array<std::array<int, 2>, 4> cw = {{{0, 0}, {0, 1}, {1, 1}, {1, 0}}};
            const auto& order = side == 1 ? ccw : cw;
            for (int k = 0; k < 4; ++k) {
                std::array<int, 3> p{};
                p[axis] = side;
                p[u] = order[k][0];
                p[v] = order[k][1];
                faces[f].corners[k] = corner_at(p[0], p[1], p[2]);
            }
            for (int k = 0; k < 4; ++k) {
                faces[f].edges[k] = edge_between(faces[f].corners[k], faces[f].corners[(k + 1) % 4]);
            }
            ++f;
        }
    }
    return faces;
}

/// True when cube edges a and b (a != b) lie on a common face.
constexpr bool share_face(int a, int b) {
    for (const Face& face : make_faces()) {
        bool has_a = false, has_b = false;
        for (int e : face.edges) {
            has_a = has_a || e == a;
            has_b = has_b || e == b;
        }
        if (has_a && has_b) return true;
    }
    return false;
}

constexpr std::array<uint16_t, 256> make_edge_table() {
    std::array<uint16_t, 256> table{};
    for (int cube = 0; cube < 256; ++cube) {
        uint16_t mask = 0;
        for (int e = 0; e < 12; ++e) {
            const bool a = (cube >> kEdges[e][0]) & 1;
            const bool b = (cube >> kEdges[e][1]) & 1;
            if (a != b) mask = static_cast<uint16_t>(mask | (1u << e));
        }
        table[cube] = mask;
    }
    return table;
}

constexpr std::array<std::array<int8_t, 16>, 256> make_tri_table() {
    const std::array<Face, 6> faces = make_faces();
    std::array<std::array<int8_t, 16>, 256> table{};
    for (int cube = 0; cube < 256; ++cube) {
        auto& row = table[cube];
        for (auto& x : row) x = -1;
        const auto inside = [cube](int corner) { return ((cube >> corner) & 1) != 0; };

        // The surface's boundary runs over the cube faces. Walking a face's edges
        // counter-clockwise (seen from outside), an "entry" edge goes outside -> inside
        // and an "exit" edge inside -> outside. The surface boundary, oriented so the
        // surface faces outside, runs inside the face from each entry to the next crossed
        // edge counter-clockwise, which is an exit; taking the NEXT one keeps the inside
        // corners of an ambiguous face apart. Every crossed edge is an entry on exactly
        // one of its two faces, so next[] is a permutation of the crossed edges.
        std::array<int, 12> next{};
        for (auto& x : next) x = -1;
        for (const Face& face : faces) {
            for (int k = 0; k < 4; ++k) {
                if (inside(face.corners[k]) || !inside(face.corners[(k + 1) % 4])) continue;  // not an entry
                int exit_edge = -1;
                for (int m = 1; m < 4 && exit_edge < 0; ++m) {
                    const int a = face.corners[(k + m) % 4];
                    const int b = face.corners[(k + m + 1) % 4];
                    if (inside(a) != inside(b)) {
                        if (!inside(a)) throw std::logic_error("crossing after an entry is not an exit");
                        exit_edge = face.edges[(k + m) % 4];
                    }
                }
                const int entry_edge = face.edges[k];
                if (exit_edge < 0 || next[entry_edge] >= 0) throw std::logic_error("bad face contour");
                next[entry_edge] = exit_edge;
            }
        }

        // Trace each closed contour and fan-triangulate it from a vertex whose diagonals
        // all cross the cube's interior: a diagonal between two edges of one face would
        // lie in that face, where the neighbouring cell can use the same vertex pair
        // (a non-manifold edge, and triangles flat in the face).
        std::array<bool, 12> used{};
        int n = 0;
        for (int start = 0; start < 12; ++start) {
            if (next[start] < 0 || used[start]) continue;
            std::array<int, 12> loop{};
            int len = 0;
            int e = start;
            do {
                if (used[e] || next[e] < 0) throw std::logic_error("contour does not close");
                used[e] = true;
                loop[len++] = e;
                e = next[e];
            } while (e != start);
            if (len < 3) throw std::logic_error("contour shorter than a triangle");
            int apex = -1;
            for (int s = 0; s < len && apex < 0; ++s) {
                bool ok = true;
                for (int i = 2; i + 1 < len; ++i) {
                    if (share_face(loop[s], loop[(s + i) % len])) ok = false;
                }
                if (ok) apex = s;
            }
            if (apex < 0) throw std::logic_error("no fan with interior diagonals");
            for (int i = 1; i + 1 < len; ++i) {
                if (n + 3 > 15) throw std::logic_error("more than five triangles");
                row[n++] = static_cast<int8_t>(loop[apex]);
                row[n++] = static_cast<int8_t>(loop[(apex + i) % len]);
                row[n++] = static_cast<int8_t>(loop[(apex + i + 1) % len]);
            }
        }
    }
    return table;
}

}  // namespace

constinit const std::array<std::array<int, 3>, 8> kCornerOffset = kCorners;
constinit const std::array<std::array<int, 2>, 12> kEdgeCorners = kEdges;
constinit const std::array<uint16_t, 256> kEdgeTable = make_edge_table();
constinit const std::array<std::array<int8_t, 16>, 256> kTriTable = make_tri_table();

}  // namespace mr::mc
