// Cameras: <Cameras> and its <Camera> elements (attributes id, type = lookAt|simple,
// handedness = left|right). A Camera reads: Position Up Gaze GazePoint (lookAt) NearPlane (simple)
// NearDistance FovY (lookAt) ImageResolution ImageName NumSamples FocusDistance ApertureSize, any
// number of <Tonemap> blocks (TMO TMOOptions Saturation Gamma Extension), and <Renderer> with its
// <RendererParams> (course hw6 path tracing). 2025 scenes add <Transformations> (the camera moved as
// an object) and per-camera MaxRecursionDepth, MinRecursionDepth, SplittingFactor. The camera frame
// is checked to stay finite.
#include <cfloat>
#include <cmath>
#include <sstream>

#include "scene/scene_walker.h"
#include "shared/type_tables.h"
#include "util/error.h"

namespace clrt::walker {
namespace {

// The image plane of a lookAt camera, from <FovY> and the resolution's aspect; returns the gaze.
Vec3 lookAtPlane(const SceneNode& n, const std::string& who, Camera& cam) {
    // The course's hw6 lookAt cameras give <Gaze> (a direction) instead of <GazePoint>; their
    // references line up with GazePoint = Position + Gaze.
    Vec3 gaze;
    auto pointNode = n.child("GazePoint"), dirNode = n.child("Gaze");
    if (pointNode && dirNode) fail(*dirNode, who + ": give <GazePoint> or <Gaze>, not both");
    if (dirNode) gaze = vec3(*dirNode);
    else gaze = vec3(*need(n, "GazePoint")) - cam.position;
    auto fovNode = need(n, "FovY");
    float fovY = number(*fovNode);
    if (!(fovY > 0 && fovY < 180)) fail(*fovNode, who + ": FovY must be in (0, 180) degrees");
    cam.top = cam.nearDistance * float(std::tan(double(fovY) * M_PI / 360.0));
    cam.bottom = -cam.top;
    cam.right = cam.top * float(cam.width) / float(cam.height);
    cam.left = -cam.right;
    return gaze;
}

// <NearPlane>'s four numbers (left right bottom top). More are read as the course's own reader read
// them (hw1 spheres.xml has "-1 1 -1 1 10"): the first four are used, with one warning naming the
// element's location. Fewer is an error.
std::vector<double> nearPlaneNumbers(const SceneNode& planeNode) {
    auto p = numbers(planeNode);
    if (p.size() < 4) return numbers(planeNode, 4);  // the error "has N values, expected 4"
    if (p.size() > 4) {
        std::ostringstream extra;
        for (size_t i = 4; i < p.size(); ++i) extra << (i > 4 ? " " : "") << p[i];
        warn(planeNode.location() + ": <NearPlane> has " + std::to_string(p.size()) +
             " values; using the first 4 (left right bottom top) and ignoring '" + extra.str() + "'");
        p.resize(4);
    }
    return p;
}

// The image plane of a simple camera, its <NearPlane> (left right bottom top); returns the gaze.
Vec3 simplePlane(const SceneNode& n, const std::string& who, Camera& cam) {
    auto gazeNode = need(n, "Gaze");
    Vec3 gaze = vec3(*gazeNode);
    auto planeNode = need(n, "NearPlane");
    auto p = nearPlaneNumbers(*planeNode);
    cam.left = float(p[0]);
    cam.right = float(p[1]);
    cam.bottom = float(p[2]);
    cam.top = float(p[3]);
    if (!(cam.left < cam.right) || !(cam.bottom < cam.top))
        fail(*planeNode, who + ": NearPlane needs left < right and bottom < top");
    return gaze;
}

// The orthonormal frame u v w (w = -gaze) from gaze and up, mirrored for a left-handed camera.
void cameraFrame(const SceneNode& n, const std::string& who, Vec3 gaze, Vec3 up, bool left, Camera& cam) {
    if (!isFinite(gaze)) fail(n, who + ": the gaze direction overflows a 32-bit float");
    if (!(cam.left >= -FLT_MAX && cam.right <= FLT_MAX && cam.bottom >= -FLT_MAX && cam.top <= FLT_MAX))
        fail(n, who + ": the image plane overflows a 32-bit float");
    if (length(unit(gaze)) == 0) fail(n, who + ": gaze direction is zero");
    cam.w = -unit(gaze);
    cam.u = unit(cross(unit(up), cam.w));
    if (length(cam.u) == 0) fail(n, who + ": Up is parallel to the gaze direction");
    if (!isFinite(cam.u) || !isFinite(cam.w)) fail(n, who + ": the camera frame overflows a 32-bit float");
    cam.v = cross(cam.w, cam.u);
    if (left) cam.u = -cam.u;
}

// The handedness attribute: true for left.
bool leftHanded(const SceneNode& n, const std::string& who) {
    auto h = n.attribute("handedness");
    if (!h) return false;
    std::string v = lower(trim(*h));
    if (v == "left") return true;
    if (v != "right") fail(n, who + ": handedness='" + *h + "' is not left or right");
    return false;
}

// ImageResolution and NearDistance.
void readImageSize(const SceneNode& n, const std::string& who, Camera& cam) {
    auto resNode = need(n, "ImageResolution");
    auto res = numbers(*resNode, 2);
    cam.width = int(toInteger(*resNode, res[0]));
    cam.height = int(toInteger(*resNode, res[1]));
    if (cam.width <= 0 || cam.height <= 0)
        fail(*resNode, who + ": ImageResolution must be positive, got " + trim(resNode->text()));
    auto nearNode = need(n, "NearDistance");
    cam.nearDistance = number(*nearNode);
    if (!(cam.nearDistance > 0)) fail(*nearNode, who + ": NearDistance must be positive");
}

// ImageName, NumSamples, FocusDistance and ApertureSize.
void readSampling(const SceneNode& n, const std::string& who, Camera& cam) {
    auto nameNode = need(n, "ImageName");
    cam.imageName = trim(nameNode->text());
    if (cam.imageName.empty()) fail(*nameNode, who + ": ImageName is empty");
    if (auto c = n.child("NumSamples")) {
        cam.numSamples = cappedInteger(*c, kMaxSamplesPerPixel);
        if (cam.numSamples < 1) fail(*c, who + ": NumSamples must be at least 1");
    }
    if (auto c = n.child("FocusDistance")) cam.focusDistance = number(*c);
    if (auto c = n.child("ApertureSize")) cam.apertureSize = number(*c);
    if (cam.focusDistance < 0 || cam.apertureSize < 0) fail(n, who + ": FocusDistance and ApertureSize must not be negative");
}

// <Transformations> inside <Camera> (2025): the camera is moved as an object. Its position by the full
// matrix, its gaze and up by the linear part; lengths (near plane, FocusDistance, ApertureSize) by the
// volume scale cbrt|det| (under a uniform scale the rays are the same, the lens scales with the
// camera). Returns true when the matrix mirrors (det < 0): the image flips horizontally, as it
// would if u were transformed too.
bool placeCamera(const Walker& w, const SceneNode& n, const std::string& who, Camera& cam, Vec3& gaze, Vec3& up) {
    auto t = n.child("Transformations");
    if (!t) return false;
    Mat4 camToWorld = transformOf(w, n);
    double det = linearDeterminant(camToWorld);
    if (!(std::fabs(det) > 0) || !std::isfinite(det)) fail(*t, who + ": its Transformations are singular");
    float s = float(std::cbrt(std::fabs(det)));
    cam.position = camToWorld.transformPoint(cam.position);
    gaze = camToWorld.transformVector(gaze);
    up = camToWorld.transformVector(up);
    for (float* len : {&cam.left, &cam.right, &cam.bottom, &cam.top, &cam.nearDistance, &cam.focusDistance, &cam.apertureSize})
        *len *= s;
    if (!isFinite(cam.position) || !isFinite(gaze) || !isFinite(up) || !std::isfinite(cam.nearDistance))
        fail(*t, who + ": the transformed camera overflows a 32-bit float");
    return det < 0;
}

// The path-tracing settings a 2025 <Camera> carries besides <Renderer>: MaxRecursionDepth (overrides
// the scene's), MinRecursionDepth and SplittingFactor (read and checked; not used, with a warning).
void readCameraPathSettings(const SceneNode& n, const std::string& who, Camera& cam) {
    if (auto c = n.child("MaxRecursionDepth")) {
        cam.maxRecursionDepth = cappedInteger(*c, kMaxRecursionDepth);
        if (cam.maxRecursionDepth < 0) fail(*c, who + ": MaxRecursionDepth must not be negative");
    }
    if (auto c = n.child("MinRecursionDepth")) {
        cam.minRecursionDepth = cappedInteger(*c, kMaxRecursionDepth);
        if (cam.minRecursionDepth < 0) fail(*c, who + ": MinRecursionDepth must not be negative");
        if (!(cam.pathMode & CLRT_PATH_RR))
            warnOnce(c->location() + ": <MinRecursionDepth> is not used: it sets where Russian roulette begins, and this "
                                     "camera plays none (RendererParams without RussianRoulette)");
    }
    if (auto c = n.child("SplittingFactor")) {
        cam.splittingFactor = cappedInteger(*c, kMaxSamplesPerPixel);
        if (cam.splittingFactor < 1) fail(*c, who + ": SplittingFactor must be at least 1");
    }
}

// The CLRT_PATH_* bits of one <RendererParams> option, or 0 if unknown. The course's 2025 scenes name MIS by
// its heuristic (MIS_POWER, MIS_BALANCE, MIS_01: the readers of its 2025 students accept these three);
// MultipleImportanceSampling is clrt's own name for MIS_POWER.
int pathOption(const std::string& tok) {
    if (tok == "NextEventEstimation") return CLRT_PATH_NEE;
    if (tok == "ImportanceSampling") return CLRT_PATH_IMPORTANCE;
    if (tok == "RussianRoulette") return CLRT_PATH_RR;
    if (tok == "MultipleImportanceSampling" || tok == "MIS_POWER") return CLRT_PATH_MIS;
    if (tok == "MIS_BALANCE") return CLRT_PATH_MIS | CLRT_PATH_MIS_BALANCE;
    if (tok == "MIS_01") return CLRT_PATH_MIS | CLRT_PATH_MIS_MAXIMUM;
    return 0;
}

// <Renderer>PathTracing</Renderer> and its optional <RendererParams> (course hw6): the CLRT_PATH_*
// bits, or 0 without <Renderer> or with <Renderer>DirectLighting</Renderer> (classic ray tracing).
// Empty or missing params: uniform sampling. MultipleImportanceSampling is clrt's own option (README
// "Path tracing"), the same as the 2025 form's MIS_POWER.
int readRenderer(const SceneNode& n, const std::string& who) {
    auto rNode = n.child("Renderer");
    auto pNode = n.child("RendererParams");
    if (!rNode) {
        if (pNode) fail(*pNode, who + ": <RendererParams> needs <Renderer>PathTracing</Renderer>");
        return 0;
    }
    std::string r = trim(rNode->text());
    if (r == "DirectLighting") {  // the course's name (2021 text) for the default, classic ray tracer
        if (pNode && !trim(pNode->text()).empty())
            fail(*pNode, who + ": <RendererParams> needs <Renderer>PathTracing</Renderer> (DirectLighting takes none)");
        return 0;
    }
    if (r != "PathTracing") fail(*rNode, who + ": unknown renderer '" + r + "' (PathTracing, DirectLighting)");
    int mode = CLRT_PATH_ON;
    if (!pNode) return mode;
    std::istringstream in(pNode->text());
    const int misBits = CLRT_PATH_MIS | CLRT_PATH_MIS_BALANCE | CLRT_PATH_MIS_MAXIMUM;
    std::string misToken;  // the MIS option seen, if any
    for (std::string tok; in >> tok;) {
        int bit = pathOption(tok);
        if (!bit)
            fail(*pNode, who + ": unknown RendererParams option '" + tok +
                             "' (NextEventEstimation, ImportanceSampling, RussianRoulette, MIS_POWER, MIS_BALANCE, MIS_01, "
                             "MultipleImportanceSampling)");
        if (bit & CLRT_PATH_MIS) {  // one heuristic per camera, under any of its names
            if (!misToken.empty() && (mode & misBits) != bit)
                fail(*pNode, who + ": RendererParams names two MIS heuristics, '" + misToken + "' and '" + tok + "'");
            misToken = tok;
        }
        mode |= bit;
    }
    return mode;
}

TonemapSettings readTonemap(Walker& w, const SceneNode& n) {
    w.checkChildren(n, {"TMO", "TMOOptions", "Saturation", "Gamma", "Extension"});
    TonemapSettings t;
    if (auto c = n.child("TMO")) {
        std::string v = lower(trim(c->text()));
        if (!lookupType(tonemapOperators(), v, t.op))
            fail(*c, "<TMO>: unknown operator '" + trim(c->text()) + "' (Photographic, ACES or Filmic)");
    }
    if (auto c = n.child("TMOOptions")) {
        auto v = numbers(*c);
        if (v.empty() || v.size() > 2)
            fail(*c, "<TMOOptions> has " + std::to_string(v.size()) + " values, expected key [burn_percent]");
        t.key = float(v[0]);
        if (v.size() > 1) t.burnPercent = float(v[1]);
        if (!(t.key > 0)) fail(*c, "<TMOOptions>: key must be positive");
        if (t.burnPercent < 0 || t.burnPercent > 100) fail(*c, "<TMOOptions>: burn_percent must be in [0, 100]");
    }
    if (auto c = n.child("Saturation")) t.saturation = number(*c);
    if (auto c = n.child("Gamma")) {
        if (lower(trim(c->text())) == "srgb") {  // some versions of the course's files
            t.srgb = true;
        } else {
            t.gamma = number(*c);
            if (!(t.gamma > 0)) fail(*c, "<Gamma> must be positive (or sRGB)");
        }
    }
    if (auto c = n.child("Extension")) t.extension = trim(c->text());
    return t;
}

void readCamera(Walker& w, const SceneNode& n) {
    w.checkChildren(n, {"Position", "Gaze", "GazePoint", "Up", "NearPlane", "NearDistance", "FovY",
                        "ImageResolution", "ImageName", "NumSamples", "FocusDistance", "ApertureSize",
                        "Tonemap", "Renderer", "RendererParams", "Transformations", "MaxRecursionDepth",
                        "MinRecursionDepth", "SplittingFactor"});
    Camera cam;
    cam.id = intAttribute(n, "id", 0);
    std::string who = describe(n);
    std::string type = lower(trim(n.attribute("type").value_or("")));
    bool lookAt = type == "lookat";
    if (!lookAt && !type.empty() && type != "simple")
        fail(n, who + ": unknown camera type '" + *n.attribute("type") + "' (lookAt or simple)");
    bool left = leftHanded(n, who);
    cam.position = vec3(*need(n, "Position"));
    Vec3 up = vec3(*need(n, "Up"));
    readImageSize(n, who, cam);
    Vec3 gaze = lookAt ? lookAtPlane(n, who, cam) : simplePlane(n, who, cam);
    readSampling(n, who, cam);
    bool mirrored = placeCamera(w, n, who, cam, gaze, up);
    cameraFrame(n, who, gaze, up, left != mirrored, cam);
    for (auto& t : n.children("Tonemap")) cam.tonemaps.push_back(readTonemap(w, *t));
    cam.pathMode = readRenderer(n, who);
    readCameraPathSettings(n, who, cam);
    w.scene.cameras.push_back(cam);
}

}  // namespace

void readCameras(Walker& w, const SceneNode& n) {
    w.readInTableOrder(n, {{"Camera", readCamera}});
}

}  // namespace clrt::walker
