// Rigid bodies' shapes: closed-form volume and inertia for the primitives, the convex hull's
// for mesh shapes (by its tetrahedra from the centroid), the drawn meshes, the surface
// samples and the signed distances (rigid_shapes.h).
#include "rigid_shapes.h"

#include <fmt/format.h>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtx/matrix_operation.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <sstream>

namespace mr {

std::string_view to_string(BodyShape s) {
    switch (s) {
        case BodyShape::Box: return "box";
        case BodyShape::Sphere: return "sphere";
        case BodyShape::Capsule: return "capsule";
        case BodyShape::ConvexMesh: return "convex_mesh";
        case BodyShape::TriangleMesh: return "triangle_mesh";
    }
    return "box";
}

namespace {

constexpr float kPi = 3.14159265358979f;
constexpr size_t kMaxHullVertices = 96;  ///< the hull is found by brute force over vertex triples

bool finite3(const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

Status check_size(const char* key, float v) {
    if (std::isfinite(v) && v > 0.0f && v <= 1000.0f) return Ok{};
    return Error{fmt::format("bodies.{}: must be in (0, 1000] (got {})", key, v)};
}

struct MeshBuilder {
    BodyMesh m;
    void tri(const Vec3& a, const Vec3& b, const Vec3& c) {  // flat-shaded
        const Vec3 n = glm::normalize(glm::cross(b - a, c - a));
        for (const Vec3& p : {a, b, c}) {
            m.indices.push_back(uint32_t(m.positions.size()));
            m.positions.push_back(p);
            m.normals.push_back(n);
        }
    }
};

// Smooth-shaded body of revolution about x: rings of (x, radius) from one pole to the other.
BodyMesh revolve(const std::vector<std::pair<Vec3, Vec3>>& rings_xr_nx, int segments) {
    // each entry: (x, r, unused) position parameters and the profile normal (nx, nr, unused)
    BodyMesh m;
    const int rings = int(rings_xr_nx.size());
    for (int i = 0; i < rings; ++i) {
        const auto& [pr, nr] = rings_xr_nx[size_t(i)];
        for (int s = 0; s <= segments; ++s) {
            const float a = 2.0f * kPi * float(s) / float(segments);
            const float c = std::cos(a), sn = std::sin(a);
            m.positions.push_back(Vec3(pr.x, pr.y * c, pr.y * sn));
            m.normals.push_back(glm::normalize(Vec3(nr.x, nr.y * c, nr.y * sn)));
        }
    }
    const uint32_t row = uint32_t(segments + 1);
    for (int i = 0; i + 1 < rings; ++i)
        for (int s = 0; s < segments; ++s) {
            const uint32_t a = uint32_t(i) * row + uint32_t(s), b = a + row;
            for (uint32_t v : {a, a + 1, b, a + 1, b + 1, b}) m.indices.push_back(v);
        }
    return m;
}

BodyMesh capsule_mesh(float r, float half_len) {
    std::vector<std::pair<Vec3, Vec3>> rings;
    const int cap = 8;
    for (int i = 0; i <= cap; ++i) {  // the -x cap, pole to equator
        const float t = 0.5f * kPi * float(i) / float(cap);
        rings.push_back({Vec3(-half_len - r * std::cos(t), r * std::sin(t), 0), Vec3(-std::cos(t), std::sin(t), 0)});
    }
    for (int i = 0; i <= cap; ++i) {  // the +x cap, equator to pole
        const float t = 0.5f * kPi * float(i) / float(cap);
        rings.push_back({Vec3(half_len + r * std::sin(t), r * std::cos(t), 0), Vec3(std::sin(t), std::cos(t), 0)});
    }
    return revolve(rings, 24);
}

BodyMesh box_mesh(const Vec3& e) {
    MeshBuilder b;
    for (int axis = 0; axis < 3; ++axis)
        for (float sgn : {-1.0f, 1.0f}) {
            Vec3 n(0.0f);
            n[axis] = sgn;
            const int u = (axis + 1) % 3, v = (axis + 2) % 3;
            Vec3 c[4];
            for (int k = 0; k < 4; ++k) {
                c[k] = n * e[axis];
                c[k][u] = ((k == 1 || k == 2) ? 1.0f : -1.0f) * e[u];
                c[k][v] = (k >= 2 ? 1.0f : -1.0f) * e[v];
            }
            if (sgn > 0) {
                b.tri(c[0], c[1], c[2]), b.tri(c[0], c[2], c[3]);
            } else {
                b.tri(c[0], c[2], c[1]), b.tri(c[0], c[3], c[2]);
            }
        }
    return b.m;
}

// Points on a unit sphere (Fibonacci lattice).
std::vector<Vec3> sphere_points(int n) {
    std::vector<Vec3> p;
    const float golden = kPi * (3.0f - std::sqrt(5.0f));
    for (int i = 0; i < n; ++i) {
        const float y = 1.0f - 2.0f * (float(i) + 0.5f) / float(n);
        const float r = std::sqrt(std::max(0.0f, 1.0f - y * y));
        p.push_back(Vec3(r * std::cos(golden * float(i)), y, r * std::sin(golden * float(i))));
    }
    return p;
}

std::vector<Vec3> box_samples(const Vec3& e) {
    std::vector<Vec3> s;
    // 5 x 5 points per face (corners and edges included once enough for the contacts).
    const int n = 4;
    for (int axis = 0; axis < 3; ++axis)
        for (float sgn : {-1.0f, 1.0f})
            for (int a = 0; a <= n; ++a)
                for (int b = 0; b <= n; ++b) {
                    Vec3 p(0.0f);
                    p[axis] = sgn * e[axis];
                    p[(axis + 1) % 3] = (2.0f * float(a) / float(n) - 1.0f) * e[(axis + 1) % 3];
                    p[(axis + 2) % 3] = (2.0f * float(b) / float(n) - 1.0f) * e[(axis + 2) % 3];
                    if (std::find(s.begin(), s.end(), p) == s.end()) s.push_back(p);
                }
    return s;
}

// The OBJ's vertices (v lines) and triangles (f lines, fans), scaled.
Status read_obj(const std::string& path, float scale, std::vector<Vec3>& v, std::vector<uint32_t>& tri) {
    std::ifstream f(path);
    if (!f) return Error{fmt::format("bodies.mesh: cannot read \"{}\"", path)};
    std::string line;
    int line_no = 0;
    while (std::getline(f, line)) {
        ++line_no;
        std::istringstream ls(line);
        std::string tag;
        ls >> tag;
        if (tag == "v") {
            Vec3 p;
            if (!(ls >> p.x >> p.y >> p.z) || !finite3(p))
                return Error{fmt::format("bodies.mesh: \"{}\" line {}: a vertex needs three finite numbers", path, line_no)};
            v.push_back(p * scale);
        } else if (tag == "f") {
            std::vector<uint32_t> face;
            std::string tok;
            while (ls >> tok) {
                long k = 0;
                try {
                    k = std::stol(tok);
                } catch (...) {
                    return Error{fmt::format("bodies.mesh: \"{}\" line {}: bad face index \"{}\"", path, line_no, tok)};
                }
                if (k < 0) k += long(v.size()) + 1;
                if (k < 1 || k > long(v.size()))
                    return Error{fmt::format("bodies.mesh: \"{}\" line {}: face index {} out of range", path, line_no, tok)};
                face.push_back(uint32_t(k - 1));
            }
            for (size_t i = 2; i < face.size(); ++i) tri.insert(tri.end(), {face[0], face[i - 1], face[i]});
        }
    }
    if (v.size() < 4 || tri.empty()) return Error{fmt::format("bodies.mesh: \"{}\" has no closed mesh (at least 4 vertices and a face)", path)};
    if (v.size() > 200000) return Error{fmt::format("bodies.mesh: \"{}\" has more than 200000 vertices", path)};
    return Ok{};
}

// The convex hull's faces of a point set: brute force over triples (few points: the
// vertices are thinned to kMaxHullVertices first, the extreme ones kept by direction).
std::vector<std::array<Vec3, 3>> hull_faces(std::vector<Vec3> pts) {
    if (pts.size() > kMaxHullVertices) {
        std::vector<Vec3> kept;
        for (const Vec3& d : sphere_points(int(kMaxHullVertices))) {
            const Vec3* best = &pts[0];
            for (const Vec3& p : pts)
                if (glm::dot(p, d) > glm::dot(*best, d)) best = &p;
            if (std::find(kept.begin(), kept.end(), *best) == kept.end()) kept.push_back(*best);
        }
        pts = kept;
    }
    std::vector<std::array<Vec3, 3>> faces;
    std::vector<glm::vec4> planes;  // found so far (normal, offset)
    const size_t n = pts.size();
    Vec3 extent(0.0f);
    for (const Vec3& p : pts) extent = glm::max(extent, glm::abs(p));
    const float eps = 1e-5f * std::max({extent.x, extent.y, extent.z, 1e-6f});
    for (size_t a = 0; a < n; ++a)
        for (size_t b = a + 1; b < n; ++b)
            for (size_t c = b + 1; c < n; ++c) {
                Vec3 nrm = glm::cross(pts[b] - pts[a], pts[c] - pts[a]);
                const float len = glm::length(nrm);
                if (len < eps * eps) continue;
                nrm /= len;
                int above = 0, below = 0;
                for (size_t k = 0; k < n && !(above && below); ++k) {
                    const float s = glm::dot(pts[k] - pts[a], nrm);
                    above += s > eps;
                    below += s < -eps;
                }
                if (above && below) continue;
                if (above) nrm = -nrm;  // outward
                const float off = glm::dot(nrm, pts[a]);
                bool seen = false;  // one polygon per supporting plane (coplanar points)
                for (const glm::vec4& pl : planes)
                    if (glm::dot(Vec3(pl), nrm) > 1.0f - 1e-5f && std::abs(pl.w - off) < eps) seen = true;
                if (seen) continue;
                planes.push_back(glm::vec4(nrm, off));
                // The plane's points in angular order around their centroid, as a fan.
                std::vector<Vec3> on;
                for (const Vec3& q : pts)
                    if (std::abs(glm::dot(q, nrm) - off) <= eps) on.push_back(q);
                Vec3 mid(0.0f);
                for (const Vec3& q : on) mid += q / float(on.size());
                const Vec3 u = glm::normalize(on[0] - mid), v = glm::cross(nrm, u);
                std::sort(on.begin(), on.end(), [&](const Vec3& p1, const Vec3& p2) {
                    return std::atan2(glm::dot(p1 - mid, v), glm::dot(p1 - mid, u)) <
                           std::atan2(glm::dot(p2 - mid, v), glm::dot(p2 - mid, u));
                });
                for (size_t k = 2; k < on.size(); ++k) faces.push_back({on[0], on[k - 1], on[k]});
            }
    return faces;
}

// Volume, centroid and inertia (unit density, about the centroid) of a closed outward
// triangle mesh, by its signed tetrahedra from the origin.
void mesh_mass(const std::vector<std::array<Vec3, 3>>& tris, float& volume, Vec3& centroid, glm::mat3& inertia) {
    double vol = 0.0;
    glm::dvec3 c(0.0);
    glm::dmat3 cov(0.0);  // second moment sum x x^T
    const glm::dmat3 canon(1.0 / 60.0, 1.0 / 120.0, 1.0 / 120.0, 1.0 / 120.0, 1.0 / 60.0, 1.0 / 120.0, 1.0 / 120.0,
                           1.0 / 120.0, 1.0 / 60.0);
    for (const auto& t : tris) {
        const glm::dmat3 A{glm::dvec3(t[0]), glm::dvec3(t[1]), glm::dvec3(t[2])};
        const double det = glm::determinant(A);
        vol += det / 6.0;
        c += det / 24.0 * (glm::dvec3(t[0]) + glm::dvec3(t[1]) + glm::dvec3(t[2]));
        cov += det * A * canon * glm::transpose(A);
    }
    volume = float(vol);
    const glm::dvec3 com = vol != 0.0 ? c / vol : glm::dvec3(0.0);
    centroid = Vec3(com);
    cov -= vol * glm::outerProduct(com, com);  // about the centroid
    const double tr = cov[0][0] + cov[1][1] + cov[2][2];
    inertia = glm::mat3(glm::dmat3(tr) - cov);
}

Status mesh_shape(const BodyDef& def, RigidShape& s) {
    std::vector<Vec3> v;
    std::vector<uint32_t> tri;
    if (auto r = read_obj(def.mesh, def.size.x, v, tri); !r) return r.error();
    const auto hull = hull_faces(v);
    if (hull.size() < 4) return Error{fmt::format("bodies.mesh: \"{}\" is flat (its hull has no volume)", def.mesh)};
    std::vector<std::array<Vec3, 3>> tris;
    if (def.shape == BodyShape::TriangleMesh) {
        for (size_t i = 0; i < tri.size(); i += 3) tris.push_back({v[tri[i]], v[tri[i + 1]], v[tri[i + 2]]});
    } else {
        tris = hull;
    }
    Vec3 com;
    mesh_mass(tris, s.volume, com, s.inertia_unit);
    if (!(s.volume > 0.0f))
        return Error{fmt::format("bodies.mesh: \"{}\" encloses no volume (open, or its faces turn inwards)", def.mesh)};
    MeshBuilder b;
    for (const auto& t : tris) b.tri(t[0] - com, t[1] - com, t[2] - com);
    for (const auto& t : hull) {
        const Vec3 n = glm::normalize(glm::cross(t[1] - t[0], t[2] - t[0]));
        s.planes.push_back(glm::vec4(n, glm::dot(n, t[0] - com)));
    }
    // Samples: the hull's vertices and its faces' centroids.
    for (const auto& t : hull)
        for (const Vec3& p : {t[0] - com, t[1] - com, t[2] - com, (t[0] + t[1] + t[2]) / 3.0f - com})
            if (std::find(s.samples.begin(), s.samples.end(), p) == s.samples.end()) s.samples.push_back(p);
    s.mesh = std::make_shared<const BodyMesh>(std::move(b.m));
    return Ok{};
}

}  // namespace

glm::quat rotation_from_degrees(const Vec3& d) {
    const Vec3 r = glm::radians(d);
    const glm::quat qx = glm::angleAxis(r.x, Vec3(1, 0, 0)), qy = glm::angleAxis(r.y, Vec3(0, 1, 0)),
                    qz = glm::angleAxis(r.z, Vec3(0, 0, 1));
    return glm::normalize(qz * qy * qx);  // x first, world axes
}

namespace {

// What a shape needs to be built without overflow (validate_body, in the scene library,
// checks every value against the [[bodies]] key table's ranges before a body is added).
Status check_shape_def(const BodyDef& d) {
    if (d.shape == BodyShape::ConvexMesh || d.shape == BodyShape::TriangleMesh) {
        if (d.mesh.empty()) return Error{fmt::format("bodies.mesh: shape = \"{}\" needs an OBJ file", to_string(d.shape))};
        return check_size("size", d.size.x);
    }
    for (int a = 0; a < (d.shape == BodyShape::Box ? 3 : 1); ++a)
        if (auto r = check_size("size", d.size[a]); !r) return r;
    if (d.shape == BodyShape::Capsule && !(std::isfinite(d.size.y) && d.size.y >= 0.0f && d.size.y <= 1000.0f))
        return Error{fmt::format("bodies.size: a capsule's length (y) must be in [0, 1000] (got {})", d.size.y)};
    if (!(std::isfinite(d.density) && d.density > 0.0f)) return Error{fmt::format("bodies.density: must be > 0 (got {})", d.density)};
    return Ok{};
}

}  // namespace

Result<RigidShape> make_shape(const BodyDef& def) {
    if (auto v = check_shape_def(def); !v) return v.error();
    RigidShape s;
    s.kind = def.shape;
    switch (def.shape) {
        case BodyShape::Box: {
            const Vec3 e = 0.5f * def.size;
            s.half = e;
            s.volume = def.size.x * def.size.y * def.size.z;
            const Vec3 q = def.size * def.size;
            s.inertia_unit = glm::mat3(s.volume / 12.0f * glm::diagonal3x3(Vec3(q.y + q.z, q.x + q.z, q.x + q.y)));
            s.mesh = std::make_shared<const BodyMesh>(box_mesh(e));
            s.samples = box_samples(e);
            break;
        }
        case BodyShape::Sphere: {
            const float r = def.size.x;
            s.half = Vec3(r, 0, 0);
            s.volume = 4.0f / 3.0f * kPi * r * r * r;
            s.inertia_unit = glm::mat3(0.4f * s.volume * r * r);
            s.mesh = std::make_shared<const BodyMesh>(capsule_mesh(r, 0.0f));
            for (const Vec3& p : sphere_points(64)) s.samples.push_back(r * p);
            break;
        }
        case BodyShape::Capsule: {
            const float r = def.size.x, l = def.size.y;
            s.half = Vec3(r, 0.5f * l, 0);
            const float vc = kPi * r * r * l, vs = 4.0f / 3.0f * kPi * r * r * r;
            s.volume = vc + vs;
            // Cylinder along x plus two hemispheres (parallel axis theorem on the caps).
            const float ix = vc * r * r / 2.0f + vs * 0.4f * r * r;
            const float iy = vc * (r * r / 4.0f + l * l / 12.0f) + vs * (0.4f * r * r + l * l / 4.0f + 3.0f * l * r / 8.0f);
            s.inertia_unit = glm::mat3(glm::diagonal3x3(Vec3(ix, iy, iy)));
            s.mesh = std::make_shared<const BodyMesh>(capsule_mesh(r, 0.5f * l));
            for (const Vec3& p : sphere_points(48)) s.samples.push_back(r * p + Vec3(p.x < 0 ? -0.5f * l : 0.5f * l, 0, 0));
            for (int i = 1; i < 8; ++i)
                for (int k = 0; k < 8; ++k) {
                    const float a = 2.0f * kPi * float(k) / 8.0f;
                    s.samples.push_back(Vec3((float(i) / 8.0f - 0.5f) * l, r * std::cos(a), r * std::sin(a)));
                }
            break;
        }
        case BodyShape::ConvexMesh:
        case BodyShape::TriangleMesh:
            if (auto r = mesh_shape(def, s); !r) return r.error();
            break;
    }
    for (const Vec3& p : s.mesh->positions) s.bound = std::max(s.bound, glm::length(p));
    for (const Vec3& p : s.samples) s.sample_extent = glm::max(s.sample_extent, glm::abs(p));
    return s;
}

float RigidShape::distance(const Vec3& p) const {  // sdf's distance, the same operations, no normal
    switch (kind) {
        case BodyShape::Box: {
            const Vec3 q = glm::abs(p) - half;
            const float lo = glm::length(glm::max(q, Vec3(0.0f)));
            if (lo > 0.0f) return lo;
            return q.x > q.y ? (q.x > q.z ? q.x : q.z) : (q.y > q.z ? q.y : q.z);
        }
        case BodyShape::Sphere:
        case BodyShape::Capsule: return glm::length(p - Vec3(std::clamp(p.x, -half.y, half.y), 0.0f, 0.0f)) - half.x;
        default: {
            float best = -1e30f;
            for (const glm::vec4& pl : planes) best = std::max(best, glm::dot(Vec3(pl), p) - pl.w);
            return best;
        }
    }
}

float RigidShape::sdf(const Vec3& p, Vec3& n) const {
    switch (kind) {
        case BodyShape::Box: {
            const Vec3 q = glm::abs(p) - half;
            const Vec3 sg(p.x < 0 ? -1.0f : 1.0f, p.y < 0 ? -1.0f : 1.0f, p.z < 0 ? -1.0f : 1.0f);
            const Vec3 out = glm::max(q, Vec3(0.0f));
            const float lo = glm::length(out);
            if (lo > 0.0f) {
                n = sg * out / lo;
                return lo;
            }
            const int a = q.x > q.y ? (q.x > q.z ? 0 : 2) : (q.y > q.z ? 1 : 2);
            n = Vec3(0.0f);
            n[a] = sg[a];
            return q[a];
        }
        case BodyShape::Sphere:
        case BodyShape::Capsule: {
            const Vec3 c(std::clamp(p.x, -half.y, half.y), 0.0f, 0.0f);
            const Vec3 d = p - c;
            const float l = glm::length(d);
            n = l > 1e-9f ? d / l : Vec3(0, 1, 0);
            return l - half.x;
        }
        default: {  // the hull's planes (exact inside, a lower bound outside)
            float best = -1e30f;
            for (const glm::vec4& pl : planes) {
                const float s = glm::dot(Vec3(pl), p) - pl.w;
                if (s > best) best = s, n = Vec3(pl);
            }
            return best;
        }
    }
}

}  // namespace mr
