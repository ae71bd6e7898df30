// src/cl/: the OpenCL layer (devices, checked calls, kernel source assembly, program build and cache, argument binding, layout check).
// program.h — an OpenCL context + queue for one device (DeviceContext) and program building:
// sources are the named cl_kernels/ files with what they #include (embedded at build time, or read
// from $CLRT_KERNEL_DIR so kernels can be edited without rebuilding), compiled with
// "-cl-std=CL1.2" plus the caller's defines and the device's quirk defines (src/cl/quirks.h), and cached as device binaries on disk
// ($CLRT_CACHE_DIR, else $XDG_CACHE_HOME/clrt, else ~/.cache/clrt; CLRT_NO_CACHE=1 disables); each
// entry carries its length and an FNV-1a 64 checksum, and a damaged entry is rebuilt and rewritten.
// $CLRT_DUMP_PROGRAM=DIR also writes each program's exact source and options string into DIR
// (scripts/gpu_compile_check.sh compiles them with clang for GPU targets).
#pragma once
#include <CL/opencl.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "cl/devices.h"
#include "cl/quirks.h"

namespace clrt {

// Owns the context and the (in-order) command queue of one device, and knows its quirks.
class DeviceContext {
public:
    explicit DeviceContext(const DeviceInfo& info, bool profiling = false);
    const DeviceInfo& info() const { return info_; }
    // The device's quirks (deviceQuirks(), read once): the defines every program built here gets, and
    // the host settings (work-group size) its launches use.
    const DeviceQuirks& quirks() const { return quirks_; }
    const cl::Device& device() const { return info_.device; }
    cl::Context& context() { return context_; }
    cl::CommandQueue& queue() { return queue_; }
    void finish();  // clFinish, checked

private:
    DeviceInfo info_;
    DeviceQuirks quirks_;
    cl::Context context_;
    cl::CommandQueue queue_;
};

// How a program was obtained.
struct BuildInfo {
    bool cacheHit = false;  // created from a cached binary
    double seconds = 0;     // wall time of the build or the binary load
    std::string options;    // the build options string
    std::string log;        // the build log of a successful build (warnings), may be empty
    std::string cacheFile;  // cache entry read or written; "" when caching is disabled
};

// A named source: (name used in #line / messages, text).
using NamedSource = std::pair<std::string, std::string>;

// The programs clrt builds. Their composition (which cl_kernels/ files) is kernelProgramRoots(), the
// one place that lists it; the renderer, the tone mapper, bench/ray_bench and the tests use it.
enum class KernelProgram {
    Render,     // the wavefront renderer (src/render/renderer.cpp)
    Tonemap,    // device tone mapping (src/output/tonemap_device.cpp)
    Intersect,  // the two intersection kernels alone (bench/ray_bench, intersection tests)
    Layout      // layout_report (src/cl/layout_check.cpp)
};
// The root files of a program; each brings in what it #includes.
const std::vector<std::string>& kernelProgramRoots(KernelProgram program);

// The sources of a program made of the given root files (by file name, e.g. "shade.cl"): every file
// preceded by the files it #includes (recursively, each once, the way include guards would have it),
// its #include lines turned into comments; each text starts with a #line marker naming its file. From
// the embedded copies, or from $CLRT_KERNEL_DIR (includes resolved relative to the including file, so
// device_types.h comes from $CLRT_KERNEL_DIR/../src/shared/). Throws clrt::Error (Device) naming the
// file if one is missing.
std::vector<NamedSource> loadKernelSources(const std::vector<std::string>& kernelFiles);
std::vector<NamedSource> loadKernelSources(KernelProgram program);

// loadKernelSources() + buildProgramFromSources().
cl::Program buildProgram(DeviceContext& dc, const std::vector<std::string>& kernelFiles,
                         const std::vector<std::string>& defines, BuildInfo* info = nullptr);
cl::Program buildProgram(DeviceContext& dc, KernelProgram program, const std::vector<std::string>& defines,
                         BuildInfo* info = nullptr);

// Builds exactly the given sources (concatenated in order; nothing is prepended except a
// `#line 1 "<name>"` marker for texts that do not start with "#line"). Defines are build options such
// as "-DCLRT_HAS_SPHERES=1"; the device's quirk defines (dc.quirks().defines) follow them, so they are
// in the options string and in the cache key. Uses the binary cache. On failure throws clrt::Error (Device) whose
// message holds the error name, the device, the options string and the full build log.
cl::Program buildProgramFromSources(DeviceContext& dc, const std::vector<NamedSource>& namedSources,
                                    const std::vector<std::string>& defines, BuildInfo* info = nullptr);

// The options string used for `defines`: the defines, then "-cl-std=CL1.2".
std::string buildOptions(const std::vector<std::string>& defines);

// The program cache folder per the environment, or "" when caching is disabled.
std::string programCacheDir();

// FNV-1a 64-bit hash (chainable through `h`).
uint64_t fnv1a64(const std::string& s, uint64_t h = 0xcbf29ce484222325ull);
uint64_t fnv1a64(const void* data, size_t size, uint64_t h = 0xcbf29ce484222325ull);

// Whether a program cache file is a complete, undamaged entry (magic, length and checksum match).
bool programCacheEntryValid(const std::string& path);

// Smallest multiple of `multiple` >= value (value itself when multiple is 0).
inline size_t roundUp(size_t value, size_t multiple) {
    return multiple == 0 ? value : (value + multiple - 1) / multiple * multiple;
}

}  // namespace clrt
