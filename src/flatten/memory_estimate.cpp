// memory_estimate.cpp — the memory estimate of memory_estimate.h: device arrays by family from the
// scene's counts (the struct sizes of shared/device_types.h times the counts flattenScene will make),
// host peaks from the flattening's own temporaries, and the check against the limits.
// The BVH's share per stored triangle is a bound measured on the shared scenes (tests/test_memory.cpp
// checks every estimate against the arrays a real flattening makes): the builder's leaves hold at most
// four triangles and fill a four-triangle leaf block 2.5 to 4 triangles deep.
#include "flatten/memory_estimate.h"

#include "util/huge_pages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <set>
#include <sstream>

#include "bvh/bvh.h"
#include "flatten/flatten.h"
#include "image/image.h"  // kMaxImageTexels
#include "image/image_size.h"
#include "shared/device_types.h"

namespace clrt {
namespace {

// Per stored triangle (or sphere): leaf blocks of four (2.2 primitives each, at least: small meshes
// fill them least) and 8-wide nodes (one per 8 primitives, at most: the Audi TT has one per 14.6,
// veachAjar 15.0); the binary tree, held while the BVH is built and collapsed (then freed).
constexpr double kLeafBlocksPerPrim = 1.0 / 2.2;
constexpr double kNodesPerPrim = 1.0 / 8.0;
constexpr double kBinaryNodesPerPrim = 0.8;  // ~2·leaves, leaves of >= 2.5 primitives
constexpr uint64_t kTrianglePair = sizeof(dev::Triangle) + sizeof(dev::TriangleShading);

// One placed instance of a two-level mesh: its record (two 3x4 rows, offsets, material...) and its
// share of the top-level tree.
constexpr uint64_t kInstanceBytes = 2 * 48 + 64 + sizeof(dev::Bvh8Node) / 2;
// What the OpenCL runtime adds per device once it renders (program and kernel objects, queues, its
// worker threads' stacks): measured on PoCL as the gap between the peak RSS of small scenes and the
// rest of this estimate (16 MB at 80k triangles).
constexpr uint64_t kRuntimeBytesPerDevice = uint64_t(20) << 20;

uint64_t imageTexels(const Scene& scene, int image) {
    if (image < 0 || size_t(image) >= scene.imagePaths.size()) return 0;
    int w = 0, h = 0;
    if (!readImageSize(scene.imagePaths[size_t(image)], w, h)) return 0;  // flattening reports it
    const uint64_t texels = uint64_t(w) * uint64_t(h);
    return texels > uint64_t(kMaxImageTexels) ? 0 : texels;  // refused by readImage, naming the file
}

bool textureImageUsed(const Scene& scene, size_t index) {
    const Texture& t = scene.textures[index];
    if (t.type != dev::TEXTURE_IMAGE || t.imageIndex < 0) return false;
    if (t.decalMode == dev::DECAL_REPLACE_BACKGROUND) return true;
    for (const Shape& s : scene.shapes)
        for (int x : s.textureIndices)
            if (size_t(x) == index) return true;
    return false;
}

// Texel atlas: every used image once as float4, once more decoded for degamma="true" maps, plus 1/3 for
// a mip chain (of either); environment maps also a half4 copy (8 B/texel) and their importance
// distributions (the map's and the cosine tables: at most six floats per texel, in lights).
void addImages(const Scene& scene, MemoryEstimate& e) {
    std::set<int> plain, env, degamma;
    std::set<std::pair<int, bool>> mip;
    for (size_t ti = 0; ti < scene.textures.size(); ++ti) {
        if (!textureImageUsed(scene, ti)) continue;
        const Texture& t = scene.textures[ti];
        plain.insert(t.imageIndex);
        if (t.degamma) degamma.insert(t.imageIndex);
        if (t.interpolation == dev::INTERP_TRILINEAR && t.decalMode != dev::DECAL_REPLACE_BACKGROUND)
            mip.insert({t.imageIndex, t.degamma});
    }
    for (const Light& l : scene.lights)
        if (l.type == dev::LIGHT_ENVIRONMENT && l.imageIndex >= 0) env.insert(l.imageIndex);
    std::set<int> all(plain);
    all.insert(env.begin(), env.end());
    uint64_t texels = 0, envTexels = 0;
    for (int i : all) texels += imageTexels(scene, i);
    for (int i : degamma) texels += imageTexels(scene, i);
    for (const auto& m : mip) texels += imageTexels(scene, m.first) / 3 + 1;
    for (int i : env) envTexels += imageTexels(scene, i);
    e.texels = texels;
    e.addHostArray(e.textures, std::max<uint64_t>(texels, 1) * sizeof(dev::float4) + envTexels * 8);  // never empty
    if (envTexels) e.addHostArray(e.lights, envTexels * 6 * sizeof(float));
}

// Triangles, spheres and planes; returns the primitives the (top or only) BVH is built over.
uint64_t addGeometry(const Scene& scene, const MemoryPlan& plan, MemoryEstimate& e, uint64_t& lightTriangles) {
    uint64_t flatTris = 0, spheres = 0, planes = 0;
    std::vector<bool> storedOnce(scene.meshes.size(), false);
    for (size_t si = 0; si < scene.shapes.size(); ++si) {
        const Shape& s = scene.shapes[si];
        if (s.type == ShapeType::Sphere) { ++spheres; continue; }
        if (s.type == ShapeType::Plane) { ++planes; continue; }
        if (s.meshIndex < 0 || size_t(s.meshIndex) >= scene.meshes.size()) continue;
        const uint64_t tris = scene.meshes[size_t(s.meshIndex)].indices.size() / 3;
        e.trianglesSeen += tris;
        const bool instanced = size_t(s.meshIndex) < plan.meshInstanced.size() && plan.meshInstanced[size_t(s.meshIndex)];
        const uint64_t floats = tris * attributeFloats(meshAttributeFlags(scene, s));
        if (!instanced) { flatTris += tris; e.attributeFloatsFlattened += floats; continue; }
        ++e.instances;
        if (!storedOnce[size_t(s.meshIndex)]) { e.trianglesStored += tris; e.attributeFloats += floats; }
        storedOnce[size_t(s.meshIndex)] = true;
    }
    for (const Light& l : scene.lights)
        if (l.type == dev::LIGHT_MESH && l.shapeIndex >= 0 && size_t(l.shapeIndex) < scene.shapes.size()) {
            const Shape& s = scene.shapes[size_t(l.shapeIndex)];
            if (s.type == ShapeType::Mesh && s.meshIndex >= 0 && size_t(s.meshIndex) < scene.meshes.size())
                lightTriangles += scene.meshes[size_t(s.meshIndex)].indices.size() / 3;
        }
    e.trianglesStored += flatTris;
    e.trianglesFlattened = flatTris;
    e.addHostArray(e.geometry, std::max<uint64_t>(1, e.trianglesStored) * sizeof(dev::Triangle));
    e.addHostArray(e.geometry, std::max<uint64_t>(1, e.trianglesStored) * sizeof(dev::TriangleShading));
    e.attributeFloats += e.attributeFloatsFlattened;
    e.addHostArray(e.geometry, std::max<uint64_t>(1, e.attributeFloats) * sizeof(float));
    e.addCopied(e.geometry, std::max<uint64_t>(1, spheres) * sizeof(dev::Sphere));
    e.addCopied(e.geometry, std::max<uint64_t>(1, planes) * sizeof(dev::Plane));
    if (e.instances) e.addCopied(e.geometry, e.instances * kInstanceBytes);
    return e.trianglesStored + spheres;
}

uint64_t leafBlocks(uint64_t prims) { return uint64_t(std::ceil(double(prims) * kLeafBlocksPerPrim) + 1); }

void addBvh(uint64_t prims, MemoryEstimate& e) {
    e.addHostArray(e.bvh, uint64_t(std::ceil(double(prims) * kNodesPerPrim) + 1) * sizeof(dev::Bvh8Node));
    e.addHostArray(e.bvh, leafBlocks(prims) * sizeof(dev::LeafBlock));
}

// What the flattening holds at its peak beyond the DeviceScene arrays it returns (flatten_geometry.cpp,
// flatten_instances.cpp): the meshes' phase (the builder's items, one per triangle, written with it;
// every triangle, flattened or of a bottom level, is written straight into its slot), the build's (items,
// primRefs and binary nodes, before any 8-wide array exists), the collapse's (the binary tree and the blocks' primitives beside the 8-wide
// nodes, before the leaf blocks) and the blocks' primitives beside the leaf blocks. The triangles are
// put in leaf order in place (an int per triangle). A bottom level is built the same way after the world
// tree, its phases bounded by the same terms (its triangles are among `prims`), and appended to the
// world tree's arrays, which then move once (worldTree: their old copy, beside the new one).
uint64_t flattenExcess(const MemoryEstimate& e, uint64_t prims) {
    const uint64_t leaves = leafBlocks(prims) * sizeof(dev::LeafBlock);
    const uint64_t blockPrims = leafBlocks(prims) * sizeof(dev::int4);
    const uint64_t binaryTree = uint64_t(double(prims) * kBinaryNodesPerPrim) * sizeof(BvhNode) + prims * sizeof(int);
    const uint64_t items = prims * sizeof(BvhItem);
    const uint64_t worldPrims = prims - (e.trianglesStored - e.trianglesFlattened) - e.instances;
    uint64_t worldTree = 0;
    if (e.instances)
        worldTree = leafBlocks(worldPrims) * sizeof(dev::LeafBlock) +
                    uint64_t(std::ceil(double(worldPrims) * kNodesPerPrim) + 1) * sizeof(dev::Bvh8Node);
    auto beyond = [](uint64_t held, uint64_t notYet) { return held > notYet ? held - notYet : 0; };
    return std::max({items, beyond(items + binaryTree, e.bvh.bytes),
                     beyond(binaryTree + blockPrims, leaves) + worldTree, blockPrims + worldTree});
}

// The renderer's per-render buffers for one camera (renderer.cpp's planBatches and ensureQueues, the
// image and the device tone mapping), as their largest case: split dielectric paths, every light's
// shadow rays within the renderer's 256 MiB budget.
uint64_t renderBytes(const Scene& scene, const MemoryPlan& plan, const Camera& cam, uint64_t& pixelsOut) {
    const uint64_t w = plan.width > 0 ? uint64_t(plan.width) : uint64_t(std::max(cam.width, 1));
    const uint64_t h = plan.height > 0 ? uint64_t(plan.height) : uint64_t(std::max(cam.height, 1));
    const uint64_t pixels = w * h, spp = uint64_t(std::max(1, plan.spp > 0 ? plan.spp : cam.numSamples));
    pixelsOut = pixels;
    const uint64_t group = std::min<uint64_t>({std::max<uint64_t>(1, (uint64_t(1) << 16) / pixels), 256, spp});
    const uint64_t batch = std::max<uint64_t>(1, std::min<uint64_t>(pixels, (uint64_t(1) << 18) / group));
    uint64_t capacity = batch * group;
    bool dielectric = false;
    for (const Material& m : scene.materials) dielectric |= m.type == dev::MATERIAL_DIELECTRIC;
    // As planBatches: at most one doubling per bounce (MaxRecursionDepth, the camera's or the scene's).
    const int maxDepth = std::min(kMaxRecursionDepth, cam.maxRecursionDepth >= 0 ? cam.maxRecursionDepth : scene.maxRecursionDepth);
    if (dielectric && spp <= 4 && cam.pathMode == 0)
        for (int split = 0; split < maxDepth && (capacity << 1) <= (uint64_t(1) << 21); ++split) capacity <<= 1;
    // paths and rays, and their child slots: 2 per path, 3 under --rr-rule course (its batch is a quarter)
    const uint64_t perPath = 4 * sizeof(dev::PathState) + 4 * sizeof(dev::Ray) + sizeof(dev::Hit) +
                             sizeof(dev::ShadingPoint) + sizeof(dev::float4) + 5 * sizeof(int) +
                             sizeof(int);  // hitInstances (with instances)
    uint64_t bytes = capacity * perPath;
    const uint64_t lights = scene.lights.size();
    if (lights) {
        uint64_t slots = 1;
        for (const Light& l : scene.lights) slots = l.type == dev::LIGHT_ENVIRONMENT ? 2 : slots;
        const uint64_t budget = (uint64_t(256) << 20) / sizeof(dev::ShadowRay) / slots;
        const uint64_t chunk = std::max<uint64_t>(1, std::min<uint64_t>(lights, budget / capacity));
        bytes += capacity * chunk * slots * sizeof(dev::ShadowRay);
    }
    return bytes + pixels * (sizeof(dev::float4) + 3 * sizeof(float) + sizeof(float) + 3);
}

}  // namespace

void MemoryEstimate::addHostArray(BufferFamily& f, uint64_t bytes) {
    f.add(bytes);
    if (bytes < kHugeMinBytes) copiedOnCpu += bytes;
}

uint64_t MemoryEstimate::largestBuffer() const {
    return std::max({geometry.largest, bvh.largest, textures.largest, lights.largest, render.largest});
}

uint64_t MemoryEstimate::hostPeak(const MemoryPlan& plan) const {
    const uint64_t copies = plan.cpuDevices ? uint64_t(std::max(plan.devices, 1)) : 0;
    const uint64_t kept = deviceScene();  // DeviceScene, alive through the render (no binary tree)
    // A CPU device uses the DeviceScene's HostArrays of >= 1 MiB in place (util/huge_pages.h); it copies
    // the rest (copiedOnCpu), or everything with CLRT_HUGE_PAGES=0.
    const uint64_t scenePerCopy = hostBuffersInPlace() ? copiedOnCpu : deviceScene();
    const uint64_t rendering = kept + copies * (scenePerCopy + render.bytes) + hostImages +
                               uint64_t(std::max(plan.devices, 1)) * kRuntimeBytesPerDevice;
    return std::max(sceneModel, plan.residentNow) + std::max(flattenTransient + deviceScene(), rendering);
}

MemoryEstimate estimateMemory(const Scene& scene, const MemoryPlan& plan) {
    MemoryEstimate e;
    for (const MeshData& m : scene.meshes)
        e.sceneModel += m.positions.capacity() * sizeof(Vec3) + m.normals.capacity() * sizeof(Vec3) +
                        m.uvs.capacity() * sizeof(Vec2) + m.indices.capacity() * sizeof(int);
    uint64_t lightTriangles = 0;
    const uint64_t prims = addGeometry(scene, plan, e, lightTriangles);
    addBvh(prims + e.instances, e);
    addImages(scene, e);
    e.addCopied(e.lights, std::max<size_t>(1, scene.lights.size()) * sizeof(dev::Light));
    e.addHostArray(e.lights, lightTriangles * 3 * sizeof(dev::float4) + scene.lights.size() * 7 * sizeof(dev::float4));
    for (const Camera& c : scene.cameras) {
        uint64_t pixels = 0;
        const uint64_t bytes = renderBytes(scene, plan, c, pixels);
        if (bytes > e.render.bytes) e.render = BufferFamily{"render", bytes, pixels * sizeof(dev::float4)};
        e.hostImages = std::max<uint64_t>(e.hostImages, pixels * (2 * 3 * sizeof(float) + 4));
    }
    e.flattenTransient = flattenExcess(e, prims + e.instances);
    return e;
}

std::string memoryProblem(const MemoryEstimate& e, const MemoryPlan& plan, const MemoryLimits& lim) {
    auto line = [&](const std::string& what, uint64_t need, const std::string& limit, uint64_t have) {
        std::ostringstream s;
        s << "needs " << formatBytes(need) << " of " << what << " (" << e.trianglesSeen << " triangles as seen, "
          << e.trianglesStored << " stored), more than " << limit << " (" << formatBytes(have) << ")";
        return s.str();
    };
    const uint64_t host = e.hostPeak(plan), device = e.devicePeak();
    if (lim.cap && host > lim.cap) return line("host memory", host, "the --max-memory limit", lim.cap);
    if (lim.cap && device > lim.cap) return line("device memory", device, "the --max-memory limit", lim.cap);
    if (lim.hostAvailable && host > lim.hostAvailable)
        return line("host memory", host, "what the machine has available", lim.hostAvailable);
    if (lim.deviceMaxAlloc && e.largestBuffer() > lim.deviceMaxAlloc)
        return line("device memory in one buffer", e.largestBuffer(),
                    "the CL_DEVICE_MAX_MEM_ALLOC_SIZE of device '" + lim.deviceName + "'", lim.deviceMaxAlloc);
    if (lim.deviceGlobal && device > lim.deviceGlobal)
        return line("device memory", device, "the CL_DEVICE_GLOBAL_MEM_SIZE of device '" + lim.deviceName + "'",
                    lim.deviceGlobal);
    return "";
}

namespace {
uint64_t procField(const char* file, const char* key) {
    std::ifstream f(file);
    std::string k;
    uint64_t kb = 0;
    for (std::string line; std::getline(f, line);) {
        std::istringstream s(line);
        if (s >> k >> kb && k == key) return kb * 1024;
    }
    return 0;
}
}  // namespace

uint64_t availableHostMemory() { return procField("/proc/meminfo", "MemAvailable:"); }
uint64_t residentBytes() { return procField("/proc/self/status", "VmRSS:"); }
uint64_t peakResidentBytes() { return procField("/proc/self/status", "VmHWM:"); }

bool parseByteSize(const std::string& s, uint64_t& bytes) {
    size_t used = 0;
    double v = 0;
    try {
        v = std::stod(s, &used);
    } catch (...) {
        return false;
    }
    std::string unit = s.substr(used);
    if (!unit.empty() && (unit.back() == 'B' || unit.back() == 'b') && unit.size() <= 2) unit.pop_back();
    if (unit.size() > 1) return false;
    const std::string units = "KMGT";
    double scale = 1;
    if (!unit.empty()) {
        const size_t k = units.find(char(std::toupper(static_cast<unsigned char>(unit[0]))));
        if (k == std::string::npos) return false;
        scale = std::pow(1024.0, double(k + 1));
    }
    const double b = v * scale;
    if (!(b >= 1) || !std::isfinite(b) || b > 1.8e19) return false;
    bytes = uint64_t(b);
    return true;
}

std::string formatBytes(uint64_t bytes) {
    const char* units[] = {"B", "KB", "MB", "GB", "TB", "PB", "EB"};
    double v = double(bytes);
    int u = 0;
    while (v >= 1024 && u < 6) { v /= 1024; ++u; }
    char buf[32];
    std::snprintf(buf, sizeof buf, u == 0 ? "%.0f %s" : "%.1f %s", v, units[u]);
    return buf;
}

}  // namespace clrt
