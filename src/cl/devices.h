// devices.h — OpenCL device discovery and selection for `clrt devices` and `clrt render --device`.
// listDevices() enumerates every device of every platform with a global index; selectDevices() turns a
// --device spec ("", "2", "cpu", "gpu", "accelerator", "all", "0,2", "platform:NAME", or a name
// substring) into devices.
#pragma once
#include <CL/opencl.hpp>

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace clrt {

struct DeviceInfo {
    int index = -1;  // global index over all platforms, in enumeration order
    cl::Platform platform;
    cl::Device device;
    std::string platformName, name, vendor, driverVersion, openclCVersion;
    cl_device_type type = 0;
    unsigned computeUnits = 0;
    uint64_t globalMem = 0, maxAlloc = 0;
    size_t maxWorkGroup = 0;
};

// "GPU", "CPU", "ACCELERATOR", "CUSTOM" or "OTHER" (first matching bit).
const char* deviceTypeName(cl_device_type type);

// Every device of every platform. A platform that fails to enumerate is skipped with a warning;
// no platform (or no ICD) at all gives an empty list.
std::vector<DeviceInfo> listDevices();

// Devices named by spec (comma-separated items, each one of: an index, "cpu" (the CPU devices of
// one implementation: PoCL's when present, else the first platform's), "gpu", "accelerator", "all"
// (every device of every platform), "platform:NAME" (every device of the platforms whose name
// contains NAME, case-insensitive, e.g. platform:portable for PoCL, platform:intel for Intel's
// runtime), or a case-insensitive substring of the device name; "" = the first GPU, else the first
// device of "cpu", else the first device). Result is in index order without duplicates. Throws clrt::Error
// (ExitCode::Device), listing the available devices, when an item names no device or none exist.
std::vector<DeviceInfo> selectDevices(const std::string& spec);

// Why no device was found, for the one error line: "no OpenCL devices found", and the cause when it
// can be seen: PoCL (registered with the ICD loader) cannot create its kernel cache directory
// ($POCL_CACHE_DIR, else $XDG_CACHE_HOME/pocl/kcache, else $HOME/.cache/pocl/kcache), which makes
// PoCL report no device at all.
std::string noDevicesMessage();

// One line per device: index, type, name, platform, compute units, global memory (MiB),
// OpenCL C version, driver version. No device: throws clrt::Error (ExitCode::Device, noDevicesMessage).
void printDevices(std::ostream& os);

}  // namespace clrt
