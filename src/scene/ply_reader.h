// PLY reader: ASCII, binary_little_endian and binary_big_endian; vertex x y z, optional nx ny nz and
// u v / s t / texture_u texture_v; faces as `vertex_indices` or `vertex_index` lists of any integer
// type, polygons fanned into triangles. Throws clrt::Error naming the file on any malformed input
// (bad header, counts that the data does not hold, index out of range, truncated binary data).
#pragma once
#include <string>

#include "scene/scene.h"

namespace clrt {
// Reads `path` into object-space MeshData (indices 0-based). Degenerate faces are kept (the
// flattening step decides what to skip); faces with fewer than 3 vertices are skipped.
MeshData readPly(const std::string& path);
}  // namespace clrt
