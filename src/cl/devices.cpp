// devices.cpp — OpenCL device enumeration, --device spec parsing and the `clrt devices` listing.
#include "cl/devices.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "cl/check.h"
#include "util/error.h"

namespace clrt {

namespace {

std::string trim(std::string s) {
    while (!s.empty() && (s.back() == '\0' || std::isspace((unsigned char)s.back()))) s.pop_back();
    size_t i = 0;
    while (i < s.size() && std::isspace((unsigned char)s[i])) ++i;
    return s.substr(i);
}

std::string lower(std::string s) {
    for (char& c : s) c = (char)std::tolower((unsigned char)c);
    return s;
}

std::string platformString(cl_platform_id p, cl_platform_info what, const char* whatName) {
    size_t n = 0;
    checkCl(clGetPlatformInfo(p, what, 0, nullptr, &n), whatName, __FILE__, __LINE__);
    std::string s(n, '\0');
    checkCl(clGetPlatformInfo(p, what, n, &s[0], nullptr), whatName, __FILE__, __LINE__);
    return trim(s);
}

std::string deviceString(cl_device_id d, cl_device_info what, const char* whatName) {
    size_t n = 0;
    checkCl(clGetDeviceInfo(d, what, 0, nullptr, &n), whatName, __FILE__, __LINE__);
    std::string s(n, '\0');
    checkCl(clGetDeviceInfo(d, what, n, &s[0], nullptr), whatName, __FILE__, __LINE__);
    return trim(s);
}

template <class T>
T deviceValue(cl_device_id d, cl_device_info what, const char* whatName) {
    T v{};
    checkCl(clGetDeviceInfo(d, what, sizeof(T), &v, nullptr), whatName, __FILE__, __LINE__);
    return v;
}

// Whether an ICD file ocl-icd would load ($OCL_ICD_VENDORS: a directory or one file; else
// /etc/OpenCL/vendors) names PoCL.
bool poclRegistered() {
    namespace fs = std::filesystem;
    const char* env = std::getenv("OCL_ICD_VENDORS");
    fs::path where = env && *env ? fs::path(env) : fs::path("/etc/OpenCL/vendors");
    std::vector<fs::path> files;
    std::error_code ec;
    if (fs::is_directory(where, ec)) {
        for (fs::directory_iterator it(where, ec), end; !ec && it != end; it.increment(ec))
            if (it->path().extension() == ".icd") files.push_back(it->path());
    } else if (fs::is_regular_file(where, ec)) {
        files.push_back(where);
    }
    for (const fs::path& f : files) {
        std::ifstream in(f);
        std::string line;
        std::getline(in, line);
        if (lower(line).find("pocl") != std::string::npos) return true;
    }
    return false;
}

// "" if PoCL's kernel cache directory exists and is writable or can be created; else what is wrong.
std::string poclCacheProblem() {
    namespace fs = std::filesystem;
    auto env = [](const char* n) -> std::string {
        const char* v = std::getenv(n);
        return v ? v : "";
    };
    fs::path dir;
    std::string from;
    if (!env("POCL_CACHE_DIR").empty()) {
        dir = env("POCL_CACHE_DIR");
        from = "POCL_CACHE_DIR";
    } else if (!env("XDG_CACHE_HOME").empty()) {
        dir = fs::path(env("XDG_CACHE_HOME")) / "pocl" / "kcache";
        from = "XDG_CACHE_HOME=" + env("XDG_CACHE_HOME");
    } else if (!env("HOME").empty()) {
        dir = fs::path(env("HOME")) / ".cache" / "pocl" / "kcache";
        from = "HOME=" + env("HOME");
    } else {
        return "";
    }
    // The nearest existing ancestor must be a directory this process can create a directory in
    // (tried: access() says yes to root even on a read-only or pseudo file system).
    std::error_code ec;
    fs::path p = dir;
    while (!p.empty() && !fs::exists(p, ec) && p != p.parent_path()) p = p.parent_path();
    if (p.empty()) p = ".";
    if (fs::is_directory(p, ec)) {
        std::string probe = (p / ".clrt-probe-XXXXXX").string();
        if (::mkdtemp(&probe[0])) {
            ::rmdir(probe.c_str());
            return "";
        }
    }
    return "PoCL cannot create its kernel cache directory " + dir.string() + " (from " + from +
           "; set POCL_CACHE_DIR or XDG_CACHE_HOME to a writable directory)";
}

std::string describeAll(const std::vector<DeviceInfo>& all) {
    if (all.empty()) return noDevicesMessage();
    std::ostringstream os;
    os << "available devices:";
    for (const DeviceInfo& d : all)
        os << " [" << d.index << "] " << deviceTypeName(d.type) << " \"" << d.name << "\" (" << d.platformName
           << ");";
    std::string s = os.str();
    s.pop_back();
    return s;
}

bool isIndex(const std::string& s) {
    return !s.empty() && std::all_of(s.begin(), s.end(), [](char c) { return std::isdigit((unsigned char)c); });
}

// The CPU implementation that "cpu" and the default spec use when several are installed (PoCL and
// Intel's runtime run on the same cores: using both at once only makes them compete). PoCL's, the
// implementation clrt is validated on, when present; else the first platform with a CPU device.
std::string preferredCpuPlatform(const std::vector<DeviceInfo>& all) {
    std::string plat;
    for (const DeviceInfo& d : all) {
        if (!(d.type & CL_DEVICE_TYPE_CPU)) continue;
        if (lower(d.platformName).find("portable computing language") != std::string::npos) return d.platformName;
        if (plat.empty()) plat = d.platformName;
    }
    return plat;
}

}  // namespace

const char* deviceTypeName(cl_device_type type) {
    if (type & CL_DEVICE_TYPE_GPU) return "GPU";
    if (type & CL_DEVICE_TYPE_CPU) return "CPU";
    if (type & CL_DEVICE_TYPE_ACCELERATOR) return "ACCELERATOR";
    if (type & CL_DEVICE_TYPE_CUSTOM) return "CUSTOM";
    return "OTHER";
}

std::vector<DeviceInfo> listDevices() {
    std::vector<DeviceInfo> out;
    cl_uint numPlatforms = 0;
    cl_int err = clGetPlatformIDs(0, nullptr, &numPlatforms);
    if (err != CL_SUCCESS || numPlatforms == 0) {
        // ocl-icd answers CL_PLATFORM_NOT_FOUND_KHR when there is no platform: that is an empty list.
        if (err != CL_SUCCESS && err != -1001 /* CL_PLATFORM_NOT_FOUND_KHR */)
            warn(clErrorMessage(err, "clGetPlatformIDs", __FILE__, __LINE__));
        return out;
    }
    std::vector<cl_platform_id> platforms(numPlatforms);
    err = clGetPlatformIDs(numPlatforms, platforms.data(), nullptr);
    if (err != CL_SUCCESS) {
        warn(clErrorMessage(err, "clGetPlatformIDs", __FILE__, __LINE__));
        return out;
    }
    for (cl_platform_id p : platforms) {
        std::vector<DeviceInfo> found;
        std::string pname = "?";
        try {
            pname = platformString(p, CL_PLATFORM_NAME, "clGetPlatformInfo(CL_PLATFORM_NAME)");
            cl_uint n = 0;
            err = clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, 0, nullptr, &n);
            if (err == CL_DEVICE_NOT_FOUND || (err == CL_SUCCESS && n == 0)) continue;
            CL_CHECK(err);
            std::vector<cl_device_id> ids(n);
            CL_CHECK(clGetDeviceIDs(p, CL_DEVICE_TYPE_ALL, n, ids.data(), nullptr));
            for (cl_device_id id : ids) {
                DeviceInfo d;
                // retainObject=true: the wrappers add their own reference (a no-op for root devices).
                d.platform = cl::Platform(p, true);
                d.device = cl::Device(id, true);
                d.platformName = pname;
                d.name = deviceString(id, CL_DEVICE_NAME, "clGetDeviceInfo(CL_DEVICE_NAME)");
                d.vendor = deviceString(id, CL_DEVICE_VENDOR, "clGetDeviceInfo(CL_DEVICE_VENDOR)");
                d.driverVersion = deviceString(id, CL_DRIVER_VERSION, "clGetDeviceInfo(CL_DRIVER_VERSION)");
                d.openclCVersion =
                    deviceString(id, CL_DEVICE_OPENCL_C_VERSION, "clGetDeviceInfo(CL_DEVICE_OPENCL_C_VERSION)");
                d.type = deviceValue<cl_device_type>(id, CL_DEVICE_TYPE, "clGetDeviceInfo(CL_DEVICE_TYPE)");
                d.computeUnits =
                    deviceValue<cl_uint>(id, CL_DEVICE_MAX_COMPUTE_UNITS, "clGetDeviceInfo(CL_DEVICE_MAX_COMPUTE_UNITS)");
                d.globalMem =
                    deviceValue<cl_ulong>(id, CL_DEVICE_GLOBAL_MEM_SIZE, "clGetDeviceInfo(CL_DEVICE_GLOBAL_MEM_SIZE)");
                d.maxAlloc = deviceValue<cl_ulong>(id, CL_DEVICE_MAX_MEM_ALLOC_SIZE,
                                                   "clGetDeviceInfo(CL_DEVICE_MAX_MEM_ALLOC_SIZE)");
                d.maxWorkGroup = deviceValue<size_t>(id, CL_DEVICE_MAX_WORK_GROUP_SIZE,
                                                     "clGetDeviceInfo(CL_DEVICE_MAX_WORK_GROUP_SIZE)");
                found.push_back(std::move(d));
            }
        } catch (const Error& e) {
            warn("skipping OpenCL platform \"" + pname + "\": " + e.what());
            continue;
        } catch (const cl::Error& e) {
            warn("skipping OpenCL platform \"" + pname + "\": " + toError(e, "", __FILE__, __LINE__).what());
            continue;
        }
        for (DeviceInfo& d : found) {
            d.index = (int)out.size();
            out.push_back(std::move(d));
        }
    }
    return out;
}

std::vector<DeviceInfo> selectDevices(const std::string& spec) {
    std::vector<DeviceInfo> all = listDevices();
    if (all.empty()) throw Error(noDevicesMessage(), ExitCode::Device);

    std::vector<bool> chosen(all.size(), false);
    const std::string cpuPlatform = preferredCpuPlatform(all);
    auto firstOfType = [&](cl_device_type t) -> int {
        for (const DeviceInfo& d : all)
            if ((d.type & t) && (t != CL_DEVICE_TYPE_CPU || d.platformName == cpuPlatform)) return d.index;
        return -1;
    };

    std::string s = trim(spec);
    if (s.empty()) {
        int i = firstOfType(CL_DEVICE_TYPE_GPU);
        if (i < 0) i = firstOfType(CL_DEVICE_TYPE_CPU);
        if (i < 0) i = firstOfType(CL_DEVICE_TYPE_ACCELERATOR);
        if (i < 0) i = 0;
        return {all[i]};
    }

    std::stringstream ss(s);
    std::string item;
    while (std::getline(ss, item, ',')) {
        item = trim(item);
        std::string key = lower(item);
        bool any = false;
        if (item.empty()) {
            throw Error("--device \"" + spec + "\": empty item in the list; " + describeAll(all), ExitCode::Device);
        } else if (isIndex(item)) {
            size_t idx = item.size() > 9 ? all.size() : std::stoul(item);
            if (idx < all.size()) chosen[idx] = any = true;
        } else if (key == "all") {
            std::fill(chosen.begin(), chosen.end(), true);
            any = true;
        } else if (key == "cpu") {  // the CPU devices of one implementation (preferredCpuPlatform)
            for (const DeviceInfo& d : all)
                if ((d.type & CL_DEVICE_TYPE_CPU) && d.platformName == cpuPlatform) chosen[d.index] = any = true;
        } else if (key == "gpu" || key == "accelerator") {
            cl_device_type t = key == "gpu" ? CL_DEVICE_TYPE_GPU : CL_DEVICE_TYPE_ACCELERATOR;
            for (const DeviceInfo& d : all)
                if (d.type & t) chosen[d.index] = any = true;
        } else if (key.compare(0, 9, "platform:") == 0 && key.size() > 9) {
            // Every device of the platforms whose name contains the rest, e.g. platform:portable (PoCL).
            for (const DeviceInfo& d : all)
                if (lower(d.platformName).find(trim(key.substr(9))) != std::string::npos) chosen[d.index] = any = true;
        } else {
            for (const DeviceInfo& d : all)
                if (lower(d.name).find(key) != std::string::npos) chosen[d.index] = any = true;
        }
        if (!any) {
            const std::string cache = poclRegistered() ? poclCacheProblem() : "";
            throw Error("--device \"" + spec + "\": \"" + item + "\" names no OpenCL device; " + describeAll(all) +
                            (cache.empty() ? "" : "; note: " + cache),
                        ExitCode::Device);
        }
    }
    std::vector<DeviceInfo> out;
    for (const DeviceInfo& d : all)
        if (chosen[d.index]) out.push_back(d);
    return out;
}

std::string noDevicesMessage() {
    const std::string cache = poclRegistered() ? poclCacheProblem() : "";
    if (!cache.empty()) return "no OpenCL devices found: " + cache;
    return "no OpenCL devices found (is an OpenCL driver / ICD installed?)";
}

void printDevices(std::ostream& os) {
    std::vector<DeviceInfo> all = listDevices();
    if (all.empty()) throw Error(noDevicesMessage(), ExitCode::Device);
    for (const DeviceInfo& d : all) {
        os << "[" << d.index << "] " << deviceTypeName(d.type) << "  " << d.name << "  (platform: " << d.platformName
           << ")  compute units: " << d.computeUnits << "  global memory: " << (d.globalMem >> 20) << " MiB  "
           << d.openclCVersion << "  driver: " << d.driverVersion << "\n";
    }
}

}  // namespace clrt
