// layout_check.h — the host's view of the device struct layouts (sizes, alignments, member offsets)
// and its comparison with what the OpenCL compiler reports (kernel layout_report in cl_kernels/layout.cl).
// The (struct, member) table is written once, as an X-macro in cl_kernels/layout.cl.
#pragma once
#include <string>
#include <vector>

#include "cl/program.h"

namespace clrt {

struct LayoutEntry {
    const char* structName;
    const char* member;  // nullptr for the struct row
    int first;           // struct row: sizeof; member row: offsetof
    int second;          // struct row: alignof; member row: sizeof(member)
};

// The host table, in the kernel's order.
const std::vector<LayoutEntry>& hostLayout();

// Builds layout.cl on dc's device, runs layout_report and returns its output (out[0] = row count,
// then two ints per row).
std::vector<int> deviceLayout(DeviceContext& dc, BuildInfo* info = nullptr);

// One human-readable line per difference between the host table and a device report
// ("Sphere.objectToWorld: offset host 64, device 80"); empty when they agree.
std::vector<std::string> layoutMismatches(const std::vector<int>& device);

// deviceLayout + layoutMismatches; throws clrt::Error (Device) listing the differences.
void verifyDeviceLayout(DeviceContext& dc);

}  // namespace clrt
