// layout_check.cpp — compile-time checks of the device structs (sizes multiple of 16, standard layout)
// and the host half of the host/device layout comparison (see layout_check.h, cl_kernels/layout.cl).
#include "cl/layout_check.h"

#include <cstddef>
#include <type_traits>

#include "cl/check.h"
#include "cl/kernel_args.h"
#include "shared/device_types.h"
#include "util/error.h"
// The (struct, member) X-macro table, shared with the kernel; only CLRT_LAYOUT_TABLE is seen here.
#include "../../cl_kernels/layout.cl"

namespace clrt {

// Every struct: size a multiple of 16, standard layout (offsetof valid), trivially copyable (memcpy).
#define CLRT_STATIC_S(T)                                                                   \
    static_assert(sizeof(dev::T) % 16 == 0, #T ": size must be a multiple of 16 bytes");   \
    static_assert(std::is_standard_layout<dev::T>::value, #T ": must be standard layout"); \
    static_assert(std::is_trivially_copyable<dev::T>::value, #T ": must be trivially copyable");
#define CLRT_STATIC_M(T, m)
CLRT_LAYOUT_TABLE(CLRT_STATIC_S, CLRT_STATIC_M)
#undef CLRT_STATIC_S
#undef CLRT_STATIC_M

const std::vector<LayoutEntry>& hostLayout() {
#define CLRT_HOST_S(T) {#T, nullptr, (int)sizeof(dev::T), (int)alignof(dev::T)},
#define CLRT_HOST_M(T, m) {#T, #m, (int)offsetof(dev::T, m), (int)sizeof(dev::T::m)},
    static const std::vector<LayoutEntry> table = {CLRT_LAYOUT_TABLE(CLRT_HOST_S, CLRT_HOST_M)};
#undef CLRT_HOST_S
#undef CLRT_HOST_M
    return table;
}

std::vector<int> deviceLayout(DeviceContext& dc, BuildInfo* info) {
    const size_t n = 1 + 2 * hostLayout().size();
    cl::Program prog = buildProgram(dc, KernelProgram::Layout, {}, info);
    KernelArgs kernel(prog, "layout_report");
    std::vector<int> out(n, -1);
    cl::Buffer buf = CL_CPP(cl::Buffer(dc.context(), CL_MEM_WRITE_ONLY, n * sizeof(int)));
    kernel.set("out", buf);
    CL_CPP(dc.queue().enqueueNDRangeKernel(kernel.ready(), cl::NullRange, cl::NDRange(1), cl::NullRange));
    CL_CPP(dc.queue().enqueueReadBuffer(buf, CL_TRUE, 0, n * sizeof(int), out.data()));
    return out;
}

std::vector<std::string> layoutMismatches(const std::vector<int>& device) {
    const std::vector<LayoutEntry>& host = hostLayout();
    std::vector<std::string> out;
    if (device.empty() || device[0] != (int)host.size()) {
        out.push_back("row count: host " + std::to_string(host.size()) + ", device " +
                      (device.empty() ? std::string("(none)") : std::to_string(device[0])));
        return out;
    }
    if (device.size() < 1 + 2 * host.size()) {
        out.push_back("device report too short");
        return out;
    }
    for (size_t i = 0; i < host.size(); ++i) {
        const LayoutEntry& e = host[i];
        int d1 = device[1 + 2 * i], d2 = device[2 + 2 * i];
        std::string where = e.member ? std::string(e.structName) + "." + e.member : std::string(e.structName);
        const char* n1 = e.member ? "offset" : "sizeof";
        const char* n2 = e.member ? "member size" : "alignof";
        if (d1 != e.first)
            out.push_back(where + ": " + n1 + " host " + std::to_string(e.first) + ", device " + std::to_string(d1));
        if (d2 != e.second)
            out.push_back(where + ": " + n2 + " host " + std::to_string(e.second) + ", device " + std::to_string(d2));
    }
    return out;
}

void verifyDeviceLayout(DeviceContext& dc) {
    std::vector<std::string> diffs = layoutMismatches(deviceLayout(dc));
    if (diffs.empty()) return;
    std::string msg = "device struct layout differs from the host on \"" + dc.info().name + "\":";
    for (const std::string& d : diffs) msg += "\n  " + d;
    throw Error(msg, ExitCode::Device);
}

}  // namespace clrt
