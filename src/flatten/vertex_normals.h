// vertex_normals.h — the vertex normals of a smooth-shaded mesh (shadingMode="smooth") in object
// space, from its MeshData alone: the normals the PLY gives, or the face normals averaged per vertex.
// Independent of any transformation, so every shape that shares the MeshData (instances, the BLAS
// of a two-level BVH) can carry the same normals to world space by its own inverse transpose.
#pragma once

#include <vector>

#include "scene/scene.h"

namespace clrt {

// One object-space normal per entry of mesh.positions, unit length, or (0, 0, 0) where none is
// defined (a vertex no triangle uses, normals that cancel, NaN/Inf input): the caller falls back to
// the face normal there. Given normals (mesh.normals, one per vertex) are normalised as they are.
// Otherwise the rule is: each triangle's cross product (b − a) × (c − a) of its object-space corners
// in index order, as it is (Area: weighted by twice its area) or normalised (Unweighted), summed at its
// three vertex indices, then normalised; degenerate triangles add nothing. Vertices are shared by index
// within the mesh, not by position (a PLY's duplicated vertices keep their own normals).
std::vector<Vec3> objectVertexNormals(const MeshData& mesh, VertexNormalWeighting weighting = VertexNormalWeighting::Area);

}  // namespace clrt
