// Scene-wide settings, the single-valued children of <Scene> (each read once: a repeated one is
// ignored). Reads: BackgroundColor, ShadowRayEpsilon, IntersectionTestEpsilon, MaxRecursionDepth,
// ZeroBasedIndexing (how VertexData indices count in Faces, Triangle Indices, Sphere Center and Plane
// Point). AmbientLight is a child of <Lights> (read_lights.cpp).
#include "scene/scene_walker.h"

namespace clrt::walker {

void readBackgroundColor(Walker& w, const SceneNode& n) { w.scene.backgroundColor = vec3(n); }

// Read (a malformed value is still an error) but not used: the intersection tests are watertight and
// need no epsilon.
void readIntersectionEpsilon(Walker&, const SceneNode& n) { (void)number(n); }

// Shadow rays start ShadowRayEpsilon (1e-3 when absent) off the surface along its geometric normal, or
// the robust offset of cl_kernels/common.cl (Ray_OffsetOrigin) where that is larger.
void readShadowRayEpsilon(Walker& w, const SceneNode& n) {
    w.scene.shadowRayEpsilon = float(number(n));
    if (!(w.scene.shadowRayEpsilon >= 0)) fail(n, "ShadowRayEpsilon must not be negative");
}

void readMaxRecursionDepth(Walker& w, const SceneNode& n) {
    w.scene.maxRecursionDepth = cappedInteger(n, kMaxRecursionDepth);
    if (w.scene.maxRecursionDepth < 0) fail(n, "MaxRecursionDepth must not be negative");
}

void readZeroBasedIndexing(Walker& w, const SceneNode& n) { w.zeroBased = boolean(n, n.text(), "ZeroBasedIndexing"); }

}  // namespace clrt::walker
