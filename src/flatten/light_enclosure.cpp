// light_enclosure.cpp — findMeshLightEnclosure (light_enclosure.h): convexity and closedness of a LightMesh's
// triangles, its openings covered by opaque coplanar scene geometry (a polygon subtracted triangle by triangle).
#include "flatten/light_enclosure.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <tuple>
#include <utility>

namespace clrt {
namespace {

struct D3 {
    double x = 0, y = 0, z = 0;
};
D3 d3(const Vec3& v) { return {v.x, v.y, v.z}; }
D3 operator-(D3 a, D3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
D3 operator+(D3 a, D3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
D3 operator*(double s, D3 a) { return {s * a.x, s * a.y, s * a.z}; }
double dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
D3 cross(D3 a, D3 b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
double norm(D3 a) { return std::sqrt(dot(a, a)); }

struct P2 {
    double x = 0, y = 0;
};
using Polygon = std::vector<P2>;  // convex, counter-clockwise

double area(const Polygon& p) {
    double a = 0;
    for (size_t i = 0; i < p.size(); ++i) {
        const P2 &u = p[i], &v = p[(i + 1) % p.size()];
        a += u.x * v.y - u.y * v.x;
    }
    return 0.5 * a;
}

// The parts of convex polygon p on the left (keepLeft) or right of the directed line a -> b.
Polygon clip(const Polygon& p, P2 a, P2 b, bool keepLeft) {
    Polygon out;
    auto side = [&](P2 q) {
        double s = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
        return keepLeft ? s : -s;
    };
    for (size_t i = 0; i < p.size(); ++i) {
        P2 u = p[i], v = p[(i + 1) % p.size()];
        double su = side(u), sv = side(v);
        if (su >= 0) out.push_back(u);
        if ((su > 0 && sv < 0) || (su < 0 && sv > 0)) {
            double t = su / (su - sv);
            out.push_back({u.x + t * (v.x - u.x), u.y + t * (v.y - u.y)});
        }
    }
    return out;
}

// A plane of the light's volume: the points x with dot(x, n) = d (n unit), the volume on the side of `inside`.
struct Plane3 {
    D3 n;
    double d = 0;
    double dist(D3 x) const { return dot(x, n) - d; }
};

// Whether scene geometry other than shape `skip` covers convex polygon `loop` (in plane `pl`) with opaque,
// unmoving surfaces lying in that plane (within tol).
bool coveredByScene(const Scene& scene, const std::vector<MeshLightEnclosures::Box>& boxes, int skip,
                    const std::vector<D3>& loop, const Plane3& pl, double tol, size_t& budget) {
    const D3 e1 = (1.0 / norm(loop[1] - loop[0])) * (loop[1] - loop[0]), e2 = cross(pl.n, e1);
    auto to2 = [&](D3 x) { return P2{dot(x - loop[0], e1), dot(x - loop[0], e2)}; };
    Polygon opening;
    for (const D3& v : loop) opening.push_back(to2(v));
    if (area(opening) < 0) std::reverse(opening.begin(), opening.end());
    const double whole = area(opening);
    D3 lo = loop[0], hi = loop[0];
    for (const D3& v : loop) {
        lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
        hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
    }
    std::vector<Polygon> left{opening};  // what no covering triangle has taken yet
    for (size_t si = 0; si < scene.shapes.size() && !left.empty(); ++si) {
        const Shape& s = scene.shapes[si];
        if (int(si) == skip || s.type == ShapeType::Sphere) continue;
        const MeshLightEnclosures::Box& b = boxes[si];
        if (b.lo[0] > hi.x + tol || b.hi[0] < lo.x - tol || b.lo[1] > hi.y + tol || b.hi[1] < lo.y - tol ||
            b.lo[2] > hi.z + tol || b.hi[2] < lo.z - tol)
            continue;
        if (s.materialIndex < 0 || size_t(s.materialIndex) >= scene.materials.size() ||
            scene.materials[size_t(s.materialIndex)].type == dev::MATERIAL_DIELECTRIC || !(s.motion == Vec3(0.0f)))
            continue;
        if (s.type == ShapeType::Plane) {
            const D3 n = d3(normalize(s.transform.transformNormal(s.normal)));
            if (std::fabs(std::fabs(dot(n, pl.n)) - 1) < 1e-6 && std::fabs(pl.dist(d3(s.transform.transformPoint(s.center)))) <= tol)
                return true;
            continue;
        }
        const MeshData& m = scene.meshes.at(size_t(s.meshIndex));
        if (m.indices.size() / 3 > budget) return false;  // the scene's reading budget spent: not enclosed
        budget -= m.indices.size() / 3;
        for (size_t t = 0; t + 2 < m.indices.size() && !left.empty(); t += 3) {
            D3 v[3];
            bool near = true, overlaps = true;
            for (int k = 0; k < 3; ++k) {
                v[k] = d3(s.transform.transformPoint(m.positions.at(size_t(m.indices[t + k]))));
                near = near && std::fabs(pl.dist(v[k])) <= tol;
            }
            if (!near) continue;
            const double axes[3][3] = {{v[0].x, v[1].x, v[2].x}, {v[0].y, v[1].y, v[2].y}, {v[0].z, v[1].z, v[2].z}};
            const double los[3] = {lo.x, lo.y, lo.z}, his[3] = {hi.x, hi.y, hi.z};
            for (int a = 0; a < 3; ++a)
                overlaps = overlaps && std::max({axes[a][0], axes[a][1], axes[a][2]}) >= los[a] - tol &&
                           std::min({axes[a][0], axes[a][1], axes[a][2]}) <= his[a] + tol;
            if (!overlaps) continue;
            P2 q[3] = {to2(v[0]), to2(v[1]), to2(v[2])};
            const double twice = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[1].y - q[0].y) * (q[2].x - q[0].x);
            if (!(std::fabs(twice) > 1e-12 * whole)) continue;  // degenerate (or not finite): covers nothing
            if (twice < 0) std::swap(q[1], q[2]);
            std::vector<Polygon> next;
            for (const Polygon& piece : left) {  // piece less the triangle: the parts right of each of its edges
                Polygon rest = piece;
                for (int e = 0; e < 3 && rest.size() >= 3; ++e) {
                    Polygon out = clip(rest, q[e], q[(e + 1) % 3], false);
                    if (out.size() >= 3 && area(out) > 1e-12 * whole) next.push_back(std::move(out));
                    rest = clip(rest, q[e], q[(e + 1) % 3], true);
                }
            }
            if (next.size() > 4096) return false;  // a cover too fragmented to follow: not enclosed
            left = std::move(next);
        }
    }
    double uncovered = 0;
    for (const Polygon& p : left) uncovered += area(p);
    return uncovered <= 1e-9 * whole;
}

// The boundary edges (shared by one triangle) as loops of vertex indices; false if they do not form loops.
bool boundaryLoops(const std::vector<std::pair<int, int>>& edges, std::vector<std::vector<int>>& loops) {
    std::map<int, std::vector<int>> next;
    for (auto [a, b] : edges) {
        next[a].push_back(b);
        next[b].push_back(a);
    }
    for (const auto& [v, nb] : next)
        if (nb.size() != 2) return false;
    std::map<int, bool> seen;
    for (const auto& [start, nb] : next) {
        if (seen[start]) continue;
        std::vector<int> loop{start};
        seen[start] = true;
        int prev = start, cur = nb[0];
        while (cur != start) {
            if (seen[cur]) return false;
            seen[cur] = true;
            loop.push_back(cur);
            const std::vector<int>& c = next[cur];
            int after = c[0] == prev ? c[1] : c[0];
            prev = cur;
            cur = after;
        }
        if (loop.size() < 3) return false;
        loops.push_back(loop);
    }
    return true;
}

bool opaqueAndStill(const Scene& scene, const Shape& s) {
    return s.materialIndex >= 0 && size_t(s.materialIndex) < scene.materials.size() &&
           scene.materials[size_t(s.materialIndex)].type != dev::MATERIAL_DIELECTRIC && s.motion == Vec3(0.0f);
}

}  // namespace

MeshLightEnclosure findMeshLightEnclosure(const Scene& scene, int lightShape, const std::vector<Vec3>& triangles) {
    return MeshLightEnclosures(scene).find(lightShape, triangles);
}

const std::vector<MeshLightEnclosures::Box>& MeshLightEnclosures::shapeBoxes() {
    if (!shapeBoxes_.empty() || scene_.shapes.empty()) return shapeBoxes_;
    std::map<int, Box> meshBox;  // object space, per MeshData
    for (const Shape& s : scene_.shapes) {
        Box w{{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};  // planes (and spheres: unread)
        if (s.type == ShapeType::Mesh && (s.meshIndex < 0 || size_t(s.meshIndex) >= scene_.meshes.size())) {
            w = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};  // no triangles: covers nothing
        } else if (s.type == ShapeType::Mesh) {
            auto it = meshBox.find(s.meshIndex);
            if (it == meshBox.end()) {
                Box o{{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
                for (const Vec3& v : scene_.meshes.at(size_t(s.meshIndex)).positions) {
                    const double c[3] = {v.x, v.y, v.z};
                    for (int a = 0; a < 3; ++a) o.lo[a] = std::min(o.lo[a], c[a]), o.hi[a] = std::max(o.hi[a], c[a]);
                }
                it = meshBox.emplace(s.meshIndex, o).first;
            }
            const Box& o = it->second;
            w = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
            for (int corner = 0; corner < 8 && o.lo[0] <= o.hi[0]; ++corner) {
                const Vec3 q = s.transform.transformPoint(Vec3(float(corner & 1 ? o.hi[0] : o.lo[0]), float(corner & 2 ? o.hi[1] : o.lo[1]),
                                                               float(corner & 4 ? o.hi[2] : o.lo[2])));
                const double c[3] = {q.x, q.y, q.z};
                for (int a = 0; a < 3; ++a) w.lo[a] = std::min(w.lo[a], c[a]), w.hi[a] = std::max(w.hi[a], c[a]);
            }
            for (int a = 0; a < 3; ++a) {  // the transform's float rounding
                const double pad = 1e-6 * std::max(std::fabs(w.lo[a]), std::fabs(w.hi[a]));
                w.lo[a] -= pad, w.hi[a] += pad;
            }
        }
        shapeBoxes_.push_back(w);
    }
    return shapeBoxes_;
}

MeshLightEnclosure MeshLightEnclosures::find(int lightShape, const std::vector<Vec3>& triangles) {
    const Scene& scene = scene_;
    MeshLightEnclosure out;
    const size_t n = triangles.size() / 3;
    if (n < 2 || n > kEnclosureMaxTriangles || !opaqueAndStill(scene, scene.shapes.at(size_t(lightShape)))) return out;
    std::vector<D3> verts;
    std::vector<int> idx;  // per triangle corner: into verts (equal positions, one vertex)
    std::map<std::tuple<float, float, float>, int> at;
    for (const Vec3& v : triangles) {
        auto [it, fresh] = at.emplace(std::make_tuple(v.x, v.y, v.z), int(verts.size()));
        if (fresh) verts.push_back(d3(v));
        idx.push_back(it->second);
    }
    D3 inside, lo = verts[0], hi = verts[0];
    double big = 0;
    for (const D3& v : verts) {
        inside = inside + (1.0 / double(verts.size())) * v;
        lo = {std::min(lo.x, v.x), std::min(lo.y, v.y), std::min(lo.z, v.z)};
        hi = {std::max(hi.x, v.x), std::max(hi.y, v.y), std::max(hi.z, v.z)};
        big = std::max({big, std::fabs(v.x), std::fabs(v.y), std::fabs(v.z)});
    }
    const double tol = 1e-5 * norm(hi - lo) + 1e-6 * big;
    // Each plane holds every vertex on the inside's side, the inside strictly.
    auto supports = [&](D3 normal, D3 point, Plane3* pl) {
        double l = norm(normal);
        if (!(l > 0)) return false;
        Plane3 p{(1.0 / l) * normal, dot((1.0 / l) * normal, point)};
        if (p.dist(inside) > 0) p = {-1.0 * p.n, -p.d};
        if (!(p.dist(inside) < -tol)) return false;
        for (const D3& v : verts)
            if (p.dist(v) > tol) return false;
        if (pl) *pl = p;
        return true;
    };
    std::map<std::pair<int, int>, int> edgeUse;
    for (size_t t = 0; t < n; ++t) {
        const int* c = &idx[3 * t];
        if (!supports(cross(verts[size_t(c[1])] - verts[size_t(c[0])], verts[size_t(c[2])] - verts[size_t(c[0])]), verts[size_t(c[0])], nullptr))
            return out;
        for (int e = 0; e < 3; ++e) ++edgeUse[std::minmax(c[e], c[(e + 1) % 3])];
    }
    std::vector<std::pair<int, int>> open;
    for (const auto& [e, uses] : edgeUse) {
        if (uses > 2) return out;
        if (uses == 1) open.push_back(e);
    }
    std::vector<std::vector<int>> loops;
    if (!boundaryLoops(open, loops)) return out;
    for (const std::vector<int>& loop : loops) {  // each opening: planar, a face of the volume, covered
        D3 normal;  // Newell's normal of the loop
        std::vector<D3> pts;
        for (size_t i = 0; i < loop.size(); ++i) {
            const D3 &a = verts[size_t(loop[i])], &b = verts[size_t(loop[(i + 1) % loop.size()])];
            normal = normal + D3{(a.y - b.y) * (a.z + b.z), (a.z - b.z) * (a.x + b.x), (a.x - b.x) * (a.y + b.y)};
            pts.push_back(a);
        }
        Plane3 pl;
        if (!supports(normal, pts[0], &pl)) return out;
        for (const D3& p : pts)
            if (std::fabs(pl.dist(p)) > tol) return out;
        if (!coveredByScene(scene, shapeBoxes(), lightShape, pts, pl, tol, budget_)) return out;
    }
    out.enclosed = true;
    out.inside = Vec3(float(inside.x), float(inside.y), float(inside.z));
    return out;
}

}  // namespace clrt
