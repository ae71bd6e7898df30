// The OpenCL C sources of cl_kernels/ and the two headers of src/shared/ they include (device_types.h,
// kernel_params.h), embedded at build time (cmake/EmbedKernels.cmake). Each text starts with a #line
// marker naming its file.
#pragma once
#include <string>
#include <vector>

namespace clrt {
struct EmbeddedSource {
    const char* name;  // file name, e.g. "intersect.cl"
    const char* path;  // path relative to the source tree, e.g. "cl_kernels/intersect.cl"
    const char* text;  // contents, starting with `#line 1 "<path>"`
};
const std::vector<EmbeddedSource>& embeddedKernelSources();
}  // namespace clrt
