// program.cpp — DeviceContext, kernel source assembly, program building and the on-disk binary cache
// (checksummed entries, written atomically; a damaged entry is rebuilt, never loaded).
#include "cl/program.h"

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cl/check.h"
#include "cl/embedded_kernels.h"
#include "util/error.h"

namespace fs = std::filesystem;

namespace clrt {

// ---- DeviceContext ----------------------------------------------------------------------------

DeviceContext::DeviceContext(const DeviceInfo& info, bool profiling) : info_(info) {
    cl_int err = CL_SUCCESS;
    cl_device_id dev = info_.device();
    cl_context_properties props[] = {CL_CONTEXT_PLATFORM, (cl_context_properties)info_.platform(), 0};
    cl_context ctx = clCreateContext(props, 1, &dev, nullptr, nullptr, &err);
    CL_CHECK(err);
    context_ = cl::Context(ctx, false);  // takes ownership
    cl_command_queue q = clCreateCommandQueue(ctx, dev, profiling ? CL_QUEUE_PROFILING_ENABLE : 0, &err);
    CL_CHECK(err);
    queue_ = cl::CommandQueue(q, false);
}

void DeviceContext::finish() { CL_CHECK(clFinish(queue_())); }

// ---- sources ----------------------------------------------------------------------------------

namespace {

std::string envOr(const char* name, const std::string& fallback = "") {
    const char* v = std::getenv(name);
    return (v && *v) ? std::string(v) : fallback;
}

std::string readFile(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw Error("cannot read kernel source " + path, ExitCode::Device);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

NamedSource fromDisk(const std::string& path) {
    return {path, "#line 1 \"" + path + "\"\n" + readFile(path)};
}

NamedSource fromEmbedded(const std::string& name) {
    const auto& all = embeddedKernelSources();
    for (const EmbeddedSource& s : all)
        if (name == s.name || name == s.path) return {s.path, s.text};
    std::string known;
    for (const EmbeddedSource& s : all) known += std::string(known.empty() ? "" : ", ") + s.name;
    throw Error("kernel source \"" + name + "\" is not embedded in this build (known: " + known + ")",
                ExitCode::Device);
}

std::string hex64(uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)v);
    return buf;
}

std::string buildLog(cl_program prog, cl_device_id dev) {
    size_t n = 0;
    if (clGetProgramBuildInfo(prog, dev, CL_PROGRAM_BUILD_LOG, 0, nullptr, &n) != CL_SUCCESS || n == 0) return "";
    std::string log(n, '\0');
    if (clGetProgramBuildInfo(prog, dev, CL_PROGRAM_BUILD_LOG, n, &log[0], nullptr) != CL_SUCCESS) return "";
    while (!log.empty() && (log.back() == '\0' || log.back() == '\n' || log.back() == ' ')) log.pop_back();
    return log;
}

// Cache entry layout (native byte order; the key names the device and driver anyway):
//   magic "CLRTBIN2" | key (u64) | payload length (u64) | FNV-1a 64 of the payload (u64) | payload.
// An entry is used only when the magic, the key, the length (the file is exactly header + payload)
// and the checksum all match, so a truncated, emptied, overwritten or bit-flipped file is never
// handed to clCreateProgramWithBinary (PoCL aborts on some corrupt binaries); it is rebuilt.
const char kMagic[8] = {'C', 'L', 'R', 'T', 'B', 'I', 'N', '2'};
const char kOldMagic[8] = {'C', 'L', 'R', 'T', 'B', 'I', 'N', '1'};  // unchecked entries of older builds
constexpr uint64_t kHeaderBytes = 32, kMaxPayload = uint64_t(1) << 31;

enum class CacheRead { Ok, Missing, Stale, Corrupt };

CacheRead readCache(const std::string& path, uint64_t key, std::vector<unsigned char>& binary) {
    std::error_code ec;
    const uint64_t fileBytes = fs::file_size(path, ec);
    if (ec) return CacheRead::Missing;
    std::ifstream in(path, std::ios::binary);
    if (!in) return CacheRead::Missing;
    char magic[8];
    uint64_t k = 0, size = 0, sum = 0;
    if (!in.read(magic, 8)) return CacheRead::Corrupt;
    if (std::memcmp(magic, kOldMagic, 8) == 0) return CacheRead::Stale;
    if (std::memcmp(magic, kMagic, 8) != 0) return CacheRead::Corrupt;
    if (!in.read((char*)&k, 8) || !in.read((char*)&size, 8) || !in.read((char*)&sum, 8)) return CacheRead::Corrupt;
    if (k != key) return CacheRead::Stale;  // a file-name collision, not damage
    if (size == 0 || size > kMaxPayload || fileBytes != kHeaderBytes + size) return CacheRead::Corrupt;
    binary.resize(size);
    if (!in.read((char*)binary.data(), (std::streamsize)size)) return CacheRead::Corrupt;
    return fnv1a64(binary.data(), binary.size()) == sum ? CacheRead::Ok : CacheRead::Corrupt;
}

// Removes temporary entries ("<key>.bin.tmp.<pid>.<n>") older than ten minutes: what a writer
// killed mid-write left behind (a younger one may belong to a writer still running).
void removeStaleTemporaries(const std::string& dir) {
    std::error_code ec;
    const auto now = fs::file_time_type::clock::now();
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
        const std::string name = it->path().filename().string();
        if (name.find(".bin.tmp.") == std::string::npos) continue;
        std::error_code e2;
        auto t = fs::last_write_time(it->path(), e2);
        if (!e2 && now - t > std::chrono::minutes(10)) fs::remove(it->path(), e2);
    }
}

// Writes the entry to a temporary file in the cache folder and renames it over `path` (atomic on
// POSIX): a reader sees the old entry or the new one, never a partial file.
void writeCache(const std::string& dir, const std::string& path, uint64_t key,
                const std::vector<unsigned char>& binary) {
    static std::atomic<unsigned> counter{0};
    std::error_code ec;
    fs::create_directories(dir, ec);
    std::string tmp = path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter++);
    bool ok = false;
    {
        std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
        uint64_t size = binary.size(), sum = fnv1a64(binary.data(), binary.size());
        if (out) {
            out.write(kMagic, 8);
            out.write((const char*)&key, 8);
            out.write((const char*)&size, 8);
            out.write((const char*)&sum, 8);
            out.write((const char*)binary.data(), (std::streamsize)binary.size());
            out.close();
            ok = !out.fail();
        }
    }
    if (ok) {
        fs::rename(tmp, path, ec);  // atomic replace on POSIX
        ok = !ec;
    }
    removeStaleTemporaries(dir);
    if (!ok) {
        fs::remove(tmp, ec);
        warnOnce("cannot write the OpenCL program cache in " + dir + " (set CLRT_CACHE_DIR or CLRT_NO_CACHE=1)");
    }
}

std::vector<unsigned char> programBinary(cl_program prog) {
    cl_uint numDevices = 0;
    CL_CHECK(clGetProgramInfo(prog, CL_PROGRAM_NUM_DEVICES, sizeof numDevices, &numDevices, nullptr));
    if (numDevices != 1) return {};
    size_t size = 0;
    CL_CHECK(clGetProgramInfo(prog, CL_PROGRAM_BINARY_SIZES, sizeof size, &size, nullptr));
    if (size == 0) return {};
    std::vector<unsigned char> bin(size);
    unsigned char* ptr = bin.data();
    CL_CHECK(clGetProgramInfo(prog, CL_PROGRAM_BINARIES, sizeof ptr, &ptr, nullptr));
    return bin;
}

// Creates and builds a program from a cached binary; an empty program when that fails.
cl::Program fromBinary(DeviceContext& dc, const std::vector<unsigned char>& bin, const std::string& options) {
    cl_device_id dev = dc.device()();
    size_t size = bin.size();
    const unsigned char* ptr = bin.data();
    cl_int status = CL_SUCCESS, err = CL_SUCCESS;
    cl_program p = clCreateProgramWithBinary(dc.context()(), 1, &dev, &size, &ptr, &status, &err);
    cl::Program prog;
    if (p) prog = cl::Program(p, false);  // takes ownership
    if (err != CL_SUCCESS || status != CL_SUCCESS || !p) return cl::Program();
    if (clBuildProgram(p, 1, &dev, options.c_str(), nullptr, nullptr) != CL_SUCCESS) return cl::Program();
    return prog;
}

}  // namespace

std::vector<NamedSource> loadKernelSources(const std::vector<std::string>& kernelFiles) {
    std::vector<NamedSource> out;
    std::string dir = envOr("CLRT_KERNEL_DIR");
    if (!dir.empty()) {
        while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
        out.push_back(fromDisk(dir + "/../src/shared/device_types.h"));
        for (const std::string& f : kernelFiles) out.push_back(fromDisk(dir + "/" + f));
    } else {
        out.push_back(fromEmbedded("device_types.h"));
        for (const std::string& f : kernelFiles) out.push_back(fromEmbedded(f));
    }
    return out;
}

std::string buildOptions(const std::vector<std::string>& defines) {
    std::string opts;
    for (const std::string& d : defines) {
        if (d.find("-cl-fast-relaxed-math") != std::string::npos)
            throw Error("build option -cl-fast-relaxed-math is not allowed (it breaks the renderer's robustness)",
                        ExitCode::Device);
        opts += d + " ";
    }
    return opts + "-cl-std=CL1.2";
}

std::string programCacheDir() {
    std::string off = envOr("CLRT_NO_CACHE");
    if (!off.empty() && off != "0") return "";
    std::string dir = envOr("CLRT_CACHE_DIR");
    if (!dir.empty()) return dir;
    std::string xdg = envOr("XDG_CACHE_HOME");
    if (!xdg.empty()) return xdg + "/clrt";
    std::string home = envOr("HOME");
    if (!home.empty()) return home + "/.cache/clrt";
    return "";
}

uint64_t fnv1a64(const void* data, size_t size, uint64_t h) {
    const unsigned char* p = static_cast<const unsigned char*>(data);
    for (size_t i = 0; i < size; ++i) {
        h ^= p[i];
        h *= 0x100000001b3ull;
    }
    return h;
}

uint64_t fnv1a64(const std::string& s, uint64_t h) { return fnv1a64(s.data(), s.size(), h); }

bool programCacheEntryValid(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    uint64_t key = 0;
    if (!in.seekg(8) || !in.read((char*)&key, 8)) return false;
    std::vector<unsigned char> bin;
    return readCache(path, key, bin) == CacheRead::Ok;
}

cl::Program buildProgram(DeviceContext& dc, const std::vector<std::string>& kernelFiles,
                         const std::vector<std::string>& defines, BuildInfo* info) {
    return buildProgramFromSources(dc, loadKernelSources(kernelFiles), defines, info);
}

cl::Program buildProgramFromSources(DeviceContext& dc, const std::vector<NamedSource>& namedSources,
                                    const std::vector<std::string>& defines, BuildInfo* info) {
    auto t0 = std::chrono::steady_clock::now();
    BuildInfo local;
    BuildInfo& bi = info ? *info : local;
    bi = BuildInfo();
    bi.options = buildOptions(defines);

    std::string source, names;
    for (const NamedSource& ns : namedSources) {
        if (ns.second.compare(0, 5, "#line") != 0) source += "#line 1 \"" + ns.first + "\"\n";
        source += ns.second;
        if (source.empty() || source.back() != '\n') source += '\n';
        names += (names.empty() ? "" : ", ") + ns.first;
    }

    const DeviceInfo& di = dc.info();
    cl_device_id dev = dc.device()();
    auto seconds = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

    // Cache lookup.
    std::string cacheDir = programCacheDir();
    uint64_t key = 0;
    if (!cacheDir.empty()) {
        key = fnv1a64(source);
        for (const std::string* s : std::initializer_list<const std::string*>{&bi.options, &di.name, &di.driverVersion, &di.platformName, &di.vendor})
            key = fnv1a64(*s, fnv1a64(std::string(1, '\0'), key));
        bi.cacheFile = cacheDir + "/" + hex64(key) + ".bin";
        std::vector<unsigned char> bin;
        const CacheRead r = readCache(bi.cacheFile, key, bin);
        if (r == CacheRead::Ok) {
            cl::Program p = fromBinary(dc, bin, bi.options);
            if (p()) {
                bi.cacheHit = true;
                bi.seconds = seconds();
                clrt::info("OpenCL program (" + names + ") loaded from cache " + bi.cacheFile);
                return p;
            }
            clrt::info("OpenCL program cache entry " + bi.cacheFile + " unusable; building from source");
        } else if (r == CacheRead::Corrupt) {
            warn("OpenCL program cache entry " + bi.cacheFile + " is damaged (length or checksum); rebuilt");
        } else if (r == CacheRead::Stale) {
            clrt::info("OpenCL program cache entry " + bi.cacheFile + " is from another build; rebuilt");
        }
    }

    // Build from source.
    cl_int err = CL_SUCCESS;
    const char* text = source.c_str();
    size_t length = source.size();
    cl_program raw = clCreateProgramWithSource(dc.context()(), 1, &text, &length, &err);
    CL_CHECK(err);
    cl::Program prog(raw, false);
    err = clBuildProgram(raw, 1, &dev, bi.options.c_str(), nullptr, nullptr);
    std::string log = buildLog(raw, dev);
    if (err != CL_SUCCESS) {
        throw Error("OpenCL program build failed: " + std::string(clErrorName(err)) + " (" + std::to_string(err) +
                        ") on device \"" + di.name + "\" (" + di.platformName + ")\n  sources: " + names +
                        "\n  options: " + bi.options + "\n  build log:\n" + (log.empty() ? "(empty)" : log),
                    ExitCode::Device);
    }
    bi.log = log;
    bi.seconds = seconds();
    clrt::info("OpenCL program (" + names + ") built in " + std::to_string(bi.seconds) + " s");
    if (!log.empty()) clrt::info("build log:\n" + log);

    if (!cacheDir.empty()) {
        std::vector<unsigned char> bin = programBinary(raw);
        if (!bin.empty()) writeCache(cacheDir, bi.cacheFile, key, bin);
    }
    return prog;
}

}  // namespace clrt
