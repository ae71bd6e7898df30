// Shared helpers for tests: the OpenCL device to test on ($CLRT_TEST_DEVICE, default "cpu" = PoCL),
// the intersection kernels' scene arguments, temporary directories, image metrics, and running the clrt binary.
#pragma once
#include <catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "cl/check.h"
#include "cl/devices.h"
#include "cl/kernel_args.h"
#include "cl/program.h"
#include "flatten/device_scene.h"
#include "image/image.h"
#include "render/renderer.h"
#include "scene/scene.h"
#include "util/error.h"

namespace clrt::test {

inline DeviceInfo testDevice() {
    const char* spec = std::getenv("CLRT_TEST_DEVICE");
    return selectDevices(spec && *spec ? spec : "cpu").front();
}

// One shared context per test process (program builds are the slow part on PoCL).
inline DeviceContext& testContext() {
    // Never destroyed: OpenCL objects released from static destructors at exit run after the
    // runtime's thread-local state is gone (oclgrind 21.10's clReleaseCommandQueue then writes to its
    // freed per-thread call stack: valgrind, and "corrupted double-linked list" aborts at exit).
    static DeviceContext* dc = new DeviceContext(testDevice());
    return *dc;
}

// A read-only copy of a host array (std::vector, HostArray) on the test context; an empty array becomes one
// zero element (OpenCL has no empty buffers).
template <class V> cl::Buffer readOnlyBuffer(const V& v) {
    using T = typename V::value_type;
    static const T zero{};
    const void* data = v.size() > 0 ? static_cast<const void*>(v.data()) : static_cast<const void*>(&zero);
    return CL_CPP(cl::Buffer(testContext().context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                             sizeof(T) * std::max<size_t>(1, v.size()), const_cast<void*>(data)));
}

// The scene arguments of intersect.cl's kernels (intersect_closest, intersect_shadow) as read-only buffers:
// the 8-wide tree, its leaf blocks, the primitives, planes, instances, and the queue length the kernels read.
struct IntersectScene {
    dev::SceneParams params{};
    cl::Buffer nodes, leaves, tris, spheres, planes, instances, queueCount;

    // Sets them on k (intersect_closest or intersect_shadow); its rays and outputs are the caller's.
    KernelArgs& bind(KernelArgs& k) const {
        return k.set("queueCount", queueCount).set("scene", params).set("nodes", nodes).set("leaves", leaves)
            .set("tris", tris).set("spheres", spheres).set("planes", planes).set("instances", instances);
    }
};

// The IntersectScene of these arrays (std::vector or HostArray each; empty ones as one zero element) for a queue
// of queueLength rays.
template <class Nodes, class Leaves, class Tris, class Spheres, class Planes, class Instances>
IntersectScene intersectScene(const dev::SceneParams& params, int queueLength, const Nodes& nodes, const Leaves& leaves,
                              const Tris& tris, const Spheres& spheres, const Planes& planes, const Instances& instances) {
    IntersectScene s;
    s.params = params;
    s.nodes = readOnlyBuffer(nodes);
    s.leaves = readOnlyBuffer(leaves);
    s.tris = readOnlyBuffer(tris);
    s.spheres = readOnlyBuffer(spheres);
    s.planes = readOnlyBuffer(planes);
    s.instances = readOnlyBuffer(instances);
    s.queueCount = readOnlyBuffer(std::vector<int>{queueLength});
    return s;
}

// Runs an element-wise test kernel on the test device: kernelSource defines
//     __kernel void NAME(const __global In* in, __global Out* out, int n)   (out[i] from in[i], i < n)
// and is built after the kernel files `files` (e.g. {"common.cl"}) with `defines` ("-D..."); returns out.
template <class Out, class In>
std::vector<Out> runElementwiseKernel(const std::vector<std::string>& files, const char* name, const char* kernelSource,
                                      const std::vector<In>& in, const std::vector<std::string>& defines = {}) {
    DeviceContext& dc = testContext();
    auto sources = loadKernelSources(files);
    sources.push_back({std::string(name) + ".cl", kernelSource});
    cl::Program program = buildProgramFromSources(dc, sources, defines);
    cl::Kernel k = CL_CPP(cl::Kernel(program, name));
    const int n = int(in.size());
    std::vector<Out> out(in.size());
    cl::Buffer ib = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR, sizeof(In) * in.size(),
                                      const_cast<In*>(in.data())));
    cl::Buffer ob = CL_CPP(cl::Buffer(dc.context(), CL_MEM_WRITE_ONLY, sizeof(Out) * out.size()));
    CL_CPP(k.setArg(0, ib));
    CL_CPP(k.setArg(1, ob));
    CL_CPP(k.setArg(2, n));
    CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(roundUp(size_t(n), 64)), cl::NDRange(64)));
    CL_CPP(dc.queue().enqueueReadBuffer(ob, CL_TRUE, 0, sizeof(Out) * out.size(), out.data()));
    return out;
}

inline std::string sharedDir() { return CLRT_SHARED_DIR; }
inline bool haveShared() { return std::filesystem::is_directory(sharedDir() + "/scenes"); }

// A whole file's bytes ("" if it cannot be read), and a file written with exactly `bytes`.
inline std::string readFileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
inline void writeFileBytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

// What one run of the clrt binary printed: its exit code, stdout and stderr together, and its
// "clrt: error:" lines (errorLine: the last one; a good error is exactly one).
struct CliResult {
    int rc = -1;
    std::string log, errorLine;
    int errorLines = 0;
};
inline CliResult cliResult(int rc, const std::string& log) {
    CliResult r;
    r.rc = rc;
    r.log = log;
    for (size_t at = 0; at < log.size();) {
        size_t end = log.find('\n', at);
        if (end == std::string::npos) end = log.size();
        if (log.compare(at, 12, "clrt: error:") == 0) {
            ++r.errorLines;
            r.errorLine = log.substr(at, end - at);
        }
        at = end + 1;
    }
    return r;
}

struct TempDir {
    std::filesystem::path path;
    TempDir() {
        std::string tmpl = (std::filesystem::temp_directory_path() / "clrt-test-XXXXXX").string();
        path = mkdtemp(tmpl.data());
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

// Flattens `scene` and renders `cam` at `spp` samples with `seed` on the test device.
// PixelSampler::Independent: --sampler independent (to compare noise with references rendered so).
inline ImageRGB renderCamera(const Scene& scene, const Camera& cam, int spp = 1, uint32_t seed = 0,
                             PixelSampler pixelSampler = PixelSampler::Stratified) {
    DeviceScene ds = flattenScene(scene);
    ds.features.zsobol = pixelSampler == PixelSampler::ZSobol;  // as clrt render --sampler zsobol builds it
    ds.features.correlatedSampler = pixelSampler == PixelSampler::Correlated;
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = spp;
    rs.seed = seed;
    rs.pixelSampler = pixelSampler;
    RenderCounters c;
    return r.render(cam, rs, c);
}

// What a Renderer built for the scene's own features (no render option's flags) says when asked to render
// with `sampler`: the Error's message, "" when it renders.
inline std::string samplerRefusal(const Scene& scene, PixelSampler sampler) {
    DeviceScene ds = flattenScene(scene);
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = 4;
    rs.pixelSampler = sampler;
    RenderCounters c;
    try {
        r.render(scene.cameras.at(0), rs, c);
    } catch (const Error& e) {
        return e.what();
    }
    return "";
}

// Renders `cam` of the flattened scene `ds` at `spp` samples through `pipeline` (fused or wavefront) on
// the test device: for tests that check both pipelines.
inline ImageRGB renderPipeline(const DeviceScene& ds, const Camera& cam, Pipeline pipeline, int spp = 1, uint32_t seed = 0) {
    Renderer r(testContext(), ds);
    RenderSettings rs;
    rs.spp = spp;
    rs.seed = seed;
    rs.pipeline = pipeline;
    RenderCounters c;
    return r.render(cam, rs, c);
}

// An image and the counters of its render (RenderCounters: ray counts, which pipeline rendered).
struct Rendered {
    ImageRGB image;
    RenderCounters counters;
};

// Renders `cam` at w x h, `spp` samples, `seed`, through pipeline `p` with the Renderer r
// (maxBatchPixels > 0: RenderSettings::maxBatchPixels, small batches).
inline Rendered renderWith(Renderer& r, Camera cam, int w, int h, int spp, uint32_t seed, Pipeline p,
                           size_t maxBatchPixels = 0, PixelSampler sampler = PixelSampler::Stratified) {
    cam.width = w;
    cam.height = h;
    RenderSettings rs;
    rs.spp = spp;
    rs.seed = seed;
    rs.pipeline = p;
    rs.pixelSampler = sampler;
    if (maxBatchPixels > 0) rs.maxBatchPixels = maxBatchPixels;
    Rendered out;
    out.image = r.render(cam, rs, out.counters);
    return out;
}

// How many floats of two images of one size differ in their bits (size_t(-1) for different sizes).
inline size_t differingFloats(const ImageRGB& a, const ImageRGB& b) {
    if (a.pixels.size() != b.pixels.size()) return size_t(-1);
    size_t n = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) n += std::memcmp(&a.pixels[i], &b.pixels[i], sizeof(float)) != 0;
    return n;
}

// The mean over pixels and channels of (a − b)² (images of one size: else an exception, a failed test).
inline double meanSquaredDiff(const ImageRGB& a, const ImageRGB& b) {
    if (a.pixels.size() != b.pixels.size()) throw std::runtime_error("meanSquaredDiff: images of different sizes");
    double se = 0;
    for (size_t i = 0; i < a.pixels.size(); ++i) {
        double d = double(a.pixels[i]) - double(b.pixels[i]);
        se += d * d;
    }
    return se / double(a.pixels.size());
}

// PSNR in dB between two 8-bit-valued images (values 0..255).
inline double psnr8(const ImageRGB& a, const ImageRGB& b) {
    double mse = meanSquaredDiff(a, b);
    return mse == 0 ? INFINITY : 10.0 * std::log10(255.0 * 255.0 / mse);
}

// The course's LDR quantisation of linear values: clamp to [0,255], then round (or floor).
inline ImageRGB quantize(const ImageRGB& img, bool floorInstead = false) {
    ImageRGB q = img;
    for (float& v : q.pixels) {
        float c = std::fmin(255.0f, std::fmax(0.0f, std::isfinite(v) ? v : 0.0f));
        v = floorInstead ? std::floor(c) : std::round(c);
    }
    return q;
}

// The --device option for the test device (CLRT_TEST_DEVICE; default: the CPU device), with its space.
inline std::string deviceArg() {
    const char* d = std::getenv("CLRT_TEST_DEVICE");
    return std::string(" --device '") + (d && *d ? d : "cpu") + "'";
}

// Runs the clrt binary with arguments; returns the exit code; output goes to `logFile`.
inline int runClrt(const std::string& args, const std::string& logFile) {
    std::string cmd = std::string(CLRT_BINARY) + " " + args + " >" + logFile + " 2>&1";
    int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// Runs `clrt ARGS` (runClrt, output to logFile), requires exit 0 (the log as the failure's message), and
// returns the pixels of the EXR it wrote at exrPath (pixels only: the EXR header holds the render time).
inline std::vector<float> renderedPixels(const std::string& args, const std::string& logFile, const std::string& exrPath) {
    const int rc = runClrt(args, logFile);
    INFO(readFileBytes(logFile));
    REQUIRE(rc == 0);
    return readImage(exrPath).pixels;
}

}  // namespace clrt::test
