// quirks.h — device quirks in one place. Tells which OpenCL implementation a device belongs to (from its
// platform name and device vendor, as listDevices() reads them) and what that implementation needs:
// the -DCLRT_QUIRK_<NAME> defines added to every program built for the device (src/cl/program.cpp,
// so they are part of the options string and of the binary-cache key) and the host settings the
// launches use (HostSettings). The quirks are one table, quirkTable() in quirks.cpp: each row names
// its implementations, the defect, and the test or script that reproduces it (docs/quirks.md).
// Kernels read a quirk only through the macros of cl_kernels/common.cl's "Device quirks" block.
// $CLRT_QUIRKS changes the table's answer for one run (comma-separated: "none" drops all, "-NAME"
// drops one, "+NAME" adds one), for reproducers and for trying a workaround on another implementation.
#pragma once
#include <CL/opencl.hpp>

#include <cstddef>
#include <string>
#include <vector>

namespace clrt {

struct DeviceInfo;

// The OpenCL implementations told apart, as bits (a quirk row names a set of them).
enum ImplementationBit : unsigned {
    kImplPocl = 1u << 0,      // Portable Computing Language (platform name), any device type
    kImplIntelCpu = 1u << 1,  // Intel's CPU runtime: platform "Intel(R) OpenCL" (also its FPGA emulation)
    kImplIntelGpu = 1u << 2,  // Intel's GPU runtime (NEO): platform "Intel(R) OpenCL Graphics"
    kImplNvidia = 1u << 3,    // "NVIDIA CUDA"
    kImplAmd = 1u << 4,       // "AMD Accelerated Parallel Processing", ROCm
    kImplApple = 1u << 5,     // "Apple"
    kImplMesa = 1u << 6,      // rusticl, Clover
    kImplOclgrind = 1u << 7,  // "Oclgrind" (a simulator)
    kImplOther = 1u << 8,     // anything else
    kImplAll = (1u << 9) - 1
};

// The implementation bit of a device from its platform name and device vendor (case-insensitive
// substrings; the platform decides first: PoCL on an Intel CPU reports the device vendor "GenuineIntel").
unsigned detectImplementation(const std::string& platformName, const std::string& deviceVendor);
// "PoCL", "Intel CPU", ... for one bit; "other" for kImplOther or an unknown value.
const char* implementationName(unsigned implementationBit);

// What the host code launches with on a device (filled in by the quirk rows that apply).
struct HostSettings {
    // Local work size of the renderer's, the fused path's and the tone mapper's launches (global sizes
    // are rounded up to it). 0: no row fixed one, the runtime chooses (cl::NullRange), no rounding.
    size_t workGroupSize = 0;
    // Programs are built on the thread that made the context only (no build on another thread while the
    // scene is flattened: src/cli/render_cmd.cpp).
    bool buildOnContextThread = false;
};

// One row of the quirk table.
struct Quirk {
    const char* name;           // NAME of the macro CLRT_QUIRK_<NAME>
    unsigned implementations;   // ImplementationBit set it applies to
    cl_device_type deviceTypes; // and of those, the device types (CL_DEVICE_TYPE_ALL: any)
    bool kernelDefine;          // the kernels read CLRT_QUIRK_<NAME> (else a host setting alone)
    const char* defect;         // what goes wrong (or costs) without it, and where
    const char* reproducer;     // the test or script that shows it
    void (*host)(HostSettings&);  // the host setting it implies, or nullptr
};
// Every known quirk, in the order their defines are emitted.
const std::vector<Quirk>& quirkTable();

// What a device gets.
struct DeviceQuirks {
    unsigned implementation = kImplOther;  // one ImplementationBit
    std::vector<std::string> names;        // the quirks that apply, in table order
    std::vector<std::string> defines;      // "-DCLRT_QUIRK_<NAME>" of those with kernelDefine
    HostSettings host;
};

// The quirks of a device of an implementation (one ImplementationBit) and type, after `overrides` (the
// $CLRT_QUIRKS syntax; "" = the table as is). Throws clrt::Error (Usage) naming the known quirks for
// an unknown name.
DeviceQuirks quirksFor(unsigned implementation, cl_device_type type, const std::string& overrides = "");
// The quirks of a device: its implementation detected, $CLRT_QUIRKS applied.
DeviceQuirks deviceQuirks(const DeviceInfo& device);

}  // namespace clrt
