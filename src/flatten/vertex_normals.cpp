// vertex_normals.cpp — object-space vertex normals of a smooth-shaded mesh (see vertex_normals.h).
// Reads a MeshData's positions, indices and given normals; nothing of the shape that places it.
#include "flatten/vertex_normals.h"

#include <cmath>

namespace clrt {
namespace {

// Unit length, or (0, 0, 0) when v has no direction (zero, NaN or Inf).
Vec3 unitOrZero(const Vec3& v) {
    const float len = length(v);
    if (!(len > 0) || !std::isfinite(len)) return Vec3(0, 0, 0);
    const Vec3 n = v / len;
    return isFinite(n) ? n : Vec3(0, 0, 0);
}

}  // namespace

std::vector<Vec3> objectVertexNormals(const MeshData& mesh, VertexNormalWeighting weighting) {
    const size_t numVertices = mesh.positions.size();
    std::vector<Vec3> nObj(numVertices, Vec3(0, 0, 0));
    if (mesh.normals.size() == numVertices) {
        for (size_t v = 0; v < numVertices; ++v) nObj[v] = unitOrZero(mesh.normals[v]);
        return nObj;
    }
    const auto valid = [&](int i) { return i >= 0 && size_t(i) < numVertices; };
    for (size_t t = 0; t + 2 < mesh.indices.size(); t += 3) {
        const int a = mesh.indices[t], b = mesh.indices[t + 1], c = mesh.indices[t + 2];
        if (!valid(a) || !valid(b) || !valid(c)) continue;
        const Vec3& pa = mesh.positions[size_t(a)];
        Vec3 faceObj = cross(mesh.positions[size_t(b)] - pa, mesh.positions[size_t(c)] - pa);  // 2·area
        if (!isFinite(faceObj)) continue;
        if (weighting == VertexNormalWeighting::Unweighted) faceObj = unitOrZero(faceObj);
        nObj[size_t(a)] += faceObj;
        nObj[size_t(b)] += faceObj;
        nObj[size_t(c)] += faceObj;
    }
    for (Vec3& n : nObj) n = unitOrZero(n);
    return nObj;
}

}  // namespace clrt
