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

DeviceContext::DeviceContext(const DeviceInfo& info, bool profiling) : info_(info), quirks_(deviceQuirks(info)) {
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

// One kernel source file: its name for messages and #line markers (the path relative to the source
// tree, or the real path when read from $CLRT_KERNEL_DIR) and its text, starting with a #line marker.
NamedSource fromDisk(const std::string& path) {
    return {path, "#line 1 \"" + path + "\"\n" + readFile(path)};
}

// An embedded source by file name ("shade.cl") or by path relative to the source tree.
const EmbeddedSource* findEmbedded(const std::string& name) {
    for (const EmbeddedSource& s : embeddedKernelSources())
        if (name == s.name || name == s.path) return &s;
    return nullptr;
}

std::string knownEmbedded() {
    std::string known;
    for (const EmbeddedSource& s : embeddedKernelSources()) known += std::string(known.empty() ? "" : ", ") + s.name;
    return known;
}

// Resolves the #include "..." lines of kernel sources, the way a preprocessor with include guards
// would: each file is emitted once, after the files it includes (recursively, in include order), and
// its #include lines become comments (same line count, so #line markers stay true). Include paths
// are relative to the including file, as for the C/C++ compiler (device_types.h is
// "../src/shared/device_types.h" from cl_kernels/). An #include inside a comment or an #if is still
// followed: kernel files write their includes plainly at the top.
class SourceAssembler {
public:
    explicit SourceAssembler(std::string dir) : dir_(std::move(dir)) {}

    // A root file by name ("shade.cl"), with everything it includes before it.
    void addRoot(const std::string& name) {
        if (dir_.empty()) {
            const EmbeddedSource* s = findEmbedded(name);
            if (!s)
                throw Error("kernel source \"" + name + "\" is not embedded in this build (known: " + knownEmbedded() +
                                ")",
                            ExitCode::Device);
            add(s->path, s->text);
        } else {
            const std::string path = fs::path(dir_ + "/" + name).lexically_normal().string();
            if (!seen(path)) add(path, fromDisk(path).second);
        }
    }
    std::vector<NamedSource> take() { return std::move(out_); }

private:
    bool seen(const std::string& path) const {
        for (const std::string& d : done_)
            if (d == path) return true;
        return false;
    }

    void add(const std::string& path, std::string text) {
        if (seen(path)) return;
        done_.push_back(path);  // before its includes: an include cycle ends here, as with guards
        size_t lineNo = 0;
        for (size_t pos = 0; pos < text.size();) {
            size_t eol = text.find('\n', pos);
            if (eol == std::string::npos) eol = text.size();
            std::string inc;
            if (parseInclude(text, pos, eol, inc)) {
                includeFile(path, lineNo, inc);
                std::string comment = "/* #include \"" + inc + "\": placed before this file by the kernel loader */";
                text.replace(pos, eol - pos, comment);
                eol = pos + comment.size();
            }
            pos = eol + 1;
            ++lineNo;
        }
        out_.push_back({path, std::move(text)});
    }

    // True if text[begin, end) is `#include "name"` (blanks allowed around '#' and 'include').
    static bool parseInclude(const std::string& text, size_t begin, size_t end, std::string& name) {
        size_t i = begin;
        auto blanks = [&] { while (i < end && (text[i] == ' ' || text[i] == '\t')) ++i; };
        blanks();
        if (i >= end || text[i] != '#') return false;
        ++i;
        blanks();
        if (text.compare(i, 7, "include") != 0) return false;
        i += 7;
        blanks();
        if (i >= end || text[i] != '"') return false;
        size_t close = text.find('"', i + 1);
        if (close == std::string::npos || close >= end) return false;
        name = text.substr(i + 1, close - i - 1);
        return true;
    }

    void includeFile(const std::string& from, size_t lineNo, const std::string& inc) {
        // lineNo counts the #line marker that starts every text: it is the file's own line number.
        const std::string path = (fs::path(from).parent_path() / inc).lexically_normal().string();
        const std::string where = from + ":" + std::to_string(lineNo) + ": #include \"" + inc + "\"";
        if (dir_.empty()) {
            for (const EmbeddedSource& s : embeddedKernelSources())
                if (path == s.path) return add(s.path, s.text);
            throw Error(where + ": " + path + " is not embedded in this build (known: " + knownEmbedded() + ")",
                        ExitCode::Device);
        }
        if (seen(path)) return;
        std::error_code ec;
        if (!fs::is_regular_file(path, ec)) throw Error(where + ": cannot read kernel source " + path, ExitCode::Device);
        add(path, fromDisk(path).second);
    }

    std::string dir_;
    std::vector<std::string> done_;
    std::vector<NamedSource> out_;
};

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

// $CLRT_DUMP_PROGRAM=DIR: every program's exact source and options go to DIR/<hash>.cl and
// DIR/<hash>.options (for compiling the same programs offline, e.g. with clang for GPU targets).
void dumpProgram(const std::string& source, const std::string& options) {
    std::string dir = envOr("CLRT_DUMP_PROGRAM");
    if (dir.empty()) return;
    std::error_code ec;
    fs::create_directories(dir, ec);
    std::string base = dir + "/" + hex64(fnv1a64(options, fnv1a64(source)));
    std::ofstream(base + ".cl", std::ios::binary) << source;
    std::ofstream(base + ".options", std::ios::binary) << options << "\n";
}

}  // namespace

std::vector<NamedSource> loadKernelSources(const std::vector<std::string>& kernelFiles) {
    std::string dir = envOr("CLRT_KERNEL_DIR");
    while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
    SourceAssembler assembler(dir);
    for (const std::string& f : kernelFiles) assembler.addRoot(f);
    return assembler.take();
}

const std::vector<std::string>& kernelProgramRoots(KernelProgram program) {
    // The one list of what each program is made of. Root files only: each brings in what it
    // #includes, before itself (render: device_types.h, common, intersect, camera, textures, envmap,
    // lights, brdf, shade, compact, fused; kernel_params.h after device_types.h).
    static const std::vector<std::string> render = {"intersect.cl", "camera.cl", "shade.cl", "compact.cl", "fused.cl", "lanes.cl"};
    static const std::vector<std::string> tonemap = {"tonemap.cl"};
    static const std::vector<std::string> intersect = {"intersect.cl"};
    static const std::vector<std::string> layout = {"layout.cl"};
    switch (program) {
    case KernelProgram::Render: return render;
    case KernelProgram::Tonemap: return tonemap;
    case KernelProgram::Intersect: return intersect;
    case KernelProgram::Layout: break;
    }
    return layout;
}

std::vector<NamedSource> loadKernelSources(KernelProgram program) {
    return loadKernelSources(kernelProgramRoots(program));
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

cl::Program buildProgram(DeviceContext& dc, KernelProgram program, const std::vector<std::string>& defines,
                         BuildInfo* info) {
    return buildProgram(dc, kernelProgramRoots(program), defines, info);
}

cl::Program buildProgramFromSources(DeviceContext& dc, const std::vector<NamedSource>& namedSources,
                                    const std::vector<std::string>& defines, BuildInfo* info) {
    auto t0 = std::chrono::steady_clock::now();
    BuildInfo local;
    BuildInfo& bi = info ? *info : local;
    bi = BuildInfo();
    std::vector<std::string> allDefines = defines;  // the caller's, then the device's quirks (the per-device hook)
    allDefines.insert(allDefines.end(), dc.quirks().defines.begin(), dc.quirks().defines.end());
    bi.options = buildOptions(allDefines);

    std::string source, names;
    for (const NamedSource& ns : namedSources) {
        if (ns.second.compare(0, 5, "#line") != 0) source += "#line 1 \"" + ns.first + "\"\n";
        source += ns.second;
        if (source.empty() || source.back() != '\n') source += '\n';
        names += (names.empty() ? "" : ", ") + ns.first;
    }

    dumpProgram(source, bi.options);
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
