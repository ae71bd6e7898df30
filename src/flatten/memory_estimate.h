// memory_estimate.h — the host and device memory a scene will need, estimated from counts before
// anything of its size is flattened or allocated (issue 30: "memory is known before it is spent"),
// and the check of that estimate against the limits (device global memory, the largest buffer a
// device allows, the machine's available memory, a --max-memory cap).
// Reads from the scene model: meshes (vertices, triangles) and the shapes that place them (triangles
// as seen), spheres, planes, LightMesh/LightSphere lights, the images of used textures (header sizes,
// mip chains of trilinear ones) and of environment lights, and the cameras' resolution and samples.
// One BufferFamily per group of device arrays, so the two-level layout (one bottom BVH per mesh)
// plugs in through MemoryPlan::meshInstanced: a mesh marked instanced counts its triangles once.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "scene/scene.h"

namespace clrt {

// How the scene will be laid out and rendered: the inputs of the estimate that are not in the scene.
struct MemoryPlan {
    // Per Scene::meshes index: true = stored once in object space with its own bottom BVH (two-level),
    // false (or missing) = flattened, its triangles copied into world space for every shape placing it.
    std::vector<bool> meshInstanced;
    int devices = 1;           // each device holds the scene once
    bool cpuDevices = true;    // device buffers live in host memory (PoCL, Intel CPU): copied ones count twice there
    int spp = 0;               // --spp (0: each camera's NumSamples)
    int width = 0, height = 0; // --resolution (0: each camera's own)
    // What the process holds before flattening (the parsed scene, the OpenCL runtime's libraries);
    // 0: the parsed meshes alone.
    uint64_t residentNow = 0;
};

// A group of device arrays: their total and the largest single buffer among them.
struct BufferFamily {
    const char* name = "";
    uint64_t bytes = 0;    // on each device
    uint64_t largest = 0;  // the largest single buffer (compared with CL_DEVICE_MAX_MEM_ALLOC_SIZE)
    void add(uint64_t b) { bytes += b; largest = b > largest ? b : largest; }
};

struct MemoryEstimate {
    uint64_t trianglesSeen = 0;    // triangles as the renderer sees them (every instance counted)
    uint64_t trianglesStored = 0;  // triangles stored on the device (an instanced mesh once)
    uint64_t trianglesFlattened = 0;  // of those, the ones flattened into world space
    uint64_t attributeFloats = 0;  // stored triangles' corner normals and uvs (TriangleShading.attributes)
    uint64_t attributeFloatsFlattened = 0;  // of those, the flattened triangles'
    uint64_t instances = 0;        // shapes placing an instanced mesh (top-level entries)
    uint64_t texels = 0;           // texels of every image loaded (mip levels included)
    // Device arrays of the scene (on each device), by family.
    BufferFamily geometry{"geometry"};  // Triangle + TriangleShading, spheres, planes, instances
    BufferFamily bvh{"bvh"};            // 8-wide nodes and leaf blocks
    BufferFamily textures{"textures"};  // the texel atlas (texture images, mip levels, environment maps)
    BufferFamily lights{"lights"};      // lights, object lights' sampling data, environment distributions
    BufferFamily render{"render"};      // per-render buffers: path queues, shadow rays, image, tone mapping
    uint64_t sceneModel = 0;       // the parsed scene (mesh arrays), resident before flattening
    uint64_t flattenTransient = 0; // what flattening and the BVH build hold at their peak, beyond the result
    uint64_t hostImages = 0;       // host copies of the largest camera's image and outputs
    uint64_t copiedOnCpu = 0;      // device arrays a CPU device copies: std::vectors, HostArrays under 1 MiB

    // A DeviceScene HostArray (used in place by CPU devices from kHugeMinBytes up) / any other array.
    void addHostArray(BufferFamily& f, uint64_t bytes);
    void addCopied(BufferFamily& f, uint64_t bytes) { f.add(bytes); copiedOnCpu += bytes; }

    uint64_t deviceScene() const { return geometry.bytes + bvh.bytes + textures.bytes + lights.bytes; }
    uint64_t devicePeak() const { return deviceScene() + render.bytes; }  // on each device
    uint64_t largestBuffer() const;
    // Host resident peak: what the process holds before flattening (plan.residentNow, at least the
    // scene model) plus the larger of the flattening's peak and the render's
    // (the DeviceScene arrays kept for the render, with every device's copies on CPU devices: its render
    // buffers, and the scene arrays too small to be used in place, or all of them with CLRT_HUGE_PAGES=0).
    uint64_t hostPeak(const MemoryPlan& plan) const;
};

MemoryEstimate estimateMemory(const Scene& scene, const MemoryPlan& plan);

// The limits one render must fit; 0 = no such limit.
struct MemoryLimits {
    uint64_t deviceGlobal = 0;    // the smallest CL_DEVICE_GLOBAL_MEM_SIZE of the devices
    uint64_t deviceMaxAlloc = 0;  // the smallest CL_DEVICE_MAX_MEM_ALLOC_SIZE
    std::string deviceName;       // the device of those figures
    uint64_t hostAvailable = 0;   // MemAvailable (/proc/meminfo) plus what the process already holds
    uint64_t cap = 0;             // --max-memory: host peak and each device's memory
};

// "" when the estimate fits, else one line: what is needed, which limit, and by how much.
std::string memoryProblem(const MemoryEstimate& e, const MemoryPlan& plan, const MemoryLimits& lim);

// MemAvailable of /proc/meminfo and this process's resident bytes (VmRSS), 0 where unknown.
uint64_t availableHostMemory();
uint64_t residentBytes();
// This process's peak resident bytes so far (VmHWM: since its exec, unlike getrusage's ru_maxrss, which
// also counts the image of a parent that forked it), 0 where unknown.
uint64_t peakResidentBytes();

// "512M", "4G", "1.5T", "1000000" (bytes; K/M/G/T are powers of 1024, an optional trailing B);
// false when malformed or zero.
bool parseByteSize(const std::string& s, uint64_t& bytes);
// "3.2 GB", "512 MB", "10.1 TB" (powers of 1024, as parseByteSize reads them).
std::string formatBytes(uint64_t bytes);

}  // namespace clrt
