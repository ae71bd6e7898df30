// test_cl.cpp — tests of the OpenCL layer (src/cl/): error names and checks, device listing and
// selection, program building (build-log errors, the binary cache, CLRT_KERNEL_DIR) and the host/device
// struct layout comparison run on a real OpenCL device (PoCL's CPU device on the development machine).
#include <catch.hpp>

#include <CL/opencl.hpp>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>

#include "cl/check.h"
#include "cl/devices.h"
#include "cl/kernel_args.h"
#include "cl/layout_check.h"
#include "cl/program.h"
#include "flatten/device_scene.h"
#include "shared/type_tables.h"
#include "test_helpers.h"
#include "util/error.h"

namespace fs = std::filesystem;
using namespace clrt;

namespace {

// Sets an environment variable for the scope, restoring the old value afterwards.
class EnvGuard {
public:
    EnvGuard(const char* name, const char* value) : name_(name) {
        const char* old = std::getenv(name);
        had_ = old != nullptr;
        if (had_) old_ = old;
        if (value)
            setenv(name, value, 1);
        else
            unsetenv(name);
    }
    ~EnvGuard() {
        if (had_)
            setenv(name_.c_str(), old_.c_str(), 1);
        else
            unsetenv(name_.c_str());
    }

private:
    std::string name_, old_;
    bool had_ = false;
};

fs::path makeTempDir(const std::string& tag) {
    auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
    fs::path p = fs::temp_directory_path() / ("clrt_test_" + tag + "_" + std::to_string(stamp));
    fs::create_directories(p);
    return p;
}

// The first CPU device (PoCL here), shared by the tests that need a context.
DeviceContext& cpuContext() {
    // Never destroyed: see testContext() in test_helpers.h.
    static DeviceContext* dc = new DeviceContext(selectDevices("cpu").at(0));
    return *dc;
}


}  // namespace

TEST_CASE("clErrorName names the standard codes", "[cl]") {
    CHECK(std::string(clErrorName(CL_SUCCESS)) == "CL_SUCCESS");
    CHECK(std::string(clErrorName(CL_OUT_OF_RESOURCES)) == "CL_OUT_OF_RESOURCES");
    CHECK(std::string(clErrorName(CL_INVALID_KERNEL_ARGS)) == "CL_INVALID_KERNEL_ARGS");
    CHECK(std::string(clErrorName(CL_BUILD_PROGRAM_FAILURE)) == "CL_BUILD_PROGRAM_FAILURE");
    CHECK(std::string(clErrorName(-1001)) == "CL_PLATFORM_NOT_FOUND_KHR");
    CHECK(std::string(clErrorName(12345)) == "CL_UNKNOWN_ERROR");
    // Every code from 0 to -19 and -30 to -68 has a real name.
    for (int c = 0; c >= -68; --c) {
        if (c < -19 && c > -30) continue;
        INFO("code " << c);
        CHECK(std::string(clErrorName(c)) != "CL_UNKNOWN_ERROR");
    }
}

TEST_CASE("CL_CHECK throws clrt::Error with name, call, file and line", "[cl]") {
    try {
        CL_CHECK(CL_INVALID_WORK_GROUP_SIZE);
        FAIL("CL_CHECK did not throw");
    } catch (const Error& e) {
        std::string msg = e.what();
        CHECK(e.code() == ExitCode::Device);
        CHECK(msg.find("CL_INVALID_WORK_GROUP_SIZE") != std::string::npos);
        CHECK(msg.find("tests/test_cl.cpp:") != std::string::npos);
    }
    CHECK_NOTHROW(CL_CHECK(CL_SUCCESS));
}

TEST_CASE("roundUp", "[cl]") {
    CHECK(roundUp(0, 64) == 0);
    CHECK(roundUp(1, 64) == 64);
    CHECK(roundUp(64, 64) == 64);
    CHECK(roundUp(65, 64) == 128);
    CHECK(roundUp(7, 0) == 7);
}

TEST_CASE("listDevices finds the PoCL CPU device", "[cl]") {
    std::vector<DeviceInfo> all = listDevices();
    REQUIRE(!all.empty());
    bool cpu = false;
    for (size_t i = 0; i < all.size(); ++i) {
        const DeviceInfo& d = all[i];
        CHECK(d.index == (int)i);
        CHECK(!d.name.empty());
        CHECK(d.computeUnits > 0);
        CHECK(d.globalMem > 0);
        CHECK(d.maxAlloc > 0);
        CHECK(d.maxWorkGroup > 0);
        CHECK(d.openclCVersion.find("OpenCL C") != std::string::npos);
        if (d.type & CL_DEVICE_TYPE_CPU) cpu = true;
    }
    CHECK(cpu);
}

TEST_CASE("selectDevices understands its specs", "[cl]") {
    std::vector<DeviceInfo> all = listDevices();
    REQUIRE(!all.empty());

    auto cpus = selectDevices("cpu");
    REQUIRE(!cpus.empty());
    for (const DeviceInfo& d : cpus) CHECK((d.type & CL_DEVICE_TYPE_CPU) != 0);
    CHECK(selectDevices("CPU").size() == cpus.size());

    auto zero = selectDevices("0");
    REQUIRE(zero.size() == 1);
    CHECK(zero[0].index == 0);
    CHECK(zero[0].name == all[0].name);

    CHECK(selectDevices("").size() == 1);
    CHECK(selectDevices("all").size() == all.size());
    CHECK(selectDevices("0,0").size() == 1);  // duplicates collapse

    // Case-insensitive name substring.
    std::string part = all[0].name.substr(0, std::min<size_t>(all[0].name.size(), 6));
    for (char& c : part) c = (char)std::toupper((unsigned char)c);
    auto byName = selectDevices(part);
    REQUIRE(!byName.empty());
    CHECK(byName[0].index == 0);

    for (const char* bad : {"nonexistent-xyz", "99", "0,nonexistent-xyz", "0,,1"}) {
        INFO("spec " << bad);
        try {
            selectDevices(bad);
            FAIL("selectDevices did not throw");
        } catch (const Error& e) {
            CHECK(e.code() == ExitCode::Device);
            CHECK(std::string(e.what()).find(all[0].name) != std::string::npos);  // lists what exists
        }
    }
}

TEST_CASE("printDevices lists every device", "[cl]") {
    std::ostringstream os;
    printDevices(os);
    std::vector<DeviceInfo> all = listDevices();
    std::string text = os.str();
    for (const DeviceInfo& d : all) {
        CHECK(text.find("[" + std::to_string(d.index) + "]") != std::string::npos);
        CHECK(text.find(d.name) != std::string::npos);
        CHECK(text.find(d.platformName) != std::string::npos);
        CHECK(text.find("MiB") != std::string::npos);
    }
}

TEST_CASE("CL_CPP converts cl::Error into clrt::Error", "[cl]") {
    DeviceContext& dc = cpuContext();
    try {
        cl::Buffer b = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_WRITE, 0));
        FAIL("zero-size buffer was accepted");
    } catch (const Error& e) {
        std::string msg = e.what();
        CHECK(e.code() == ExitCode::Device);
        CHECK(msg.find("CL_INVALID_BUFFER_SIZE") != std::string::npos);
        CHECK(msg.find("tests/test_cl.cpp:") != std::string::npos);
    }
}

TEST_CASE("a program with a syntax error reports the build log and the file name", "[cl]") {
    DeviceContext& dc = cpuContext();
    EnvGuard noCache("CLRT_NO_CACHE", "1");
    std::vector<NamedSource> srcs = {{"cl_kernels/broken_test.cl", "__kernel void k(__global int* o) {\n"
                                                                     "  o[0] = 1\n"
                                                                     "}\n"}};
    try {
        buildProgramFromSources(dc, srcs, {"-DCLRT_TEST_DEFINE=1"});
        FAIL("broken program built");
    } catch (const Error& e) {
        std::string msg = e.what();
        INFO(msg);
        CHECK(e.code() == ExitCode::Device);
        CHECK(msg.find("CL_BUILD_PROGRAM_FAILURE") != std::string::npos);
        CHECK(msg.find("cl_kernels/broken_test.cl:2") != std::string::npos);  // the log names file:line
        CHECK(msg.find("-DCLRT_TEST_DEFINE=1 -cl-std=CL1.2") != std::string::npos);
        CHECK(msg.find("build log") != std::string::npos);
    }
}

TEST_CASE("build options never include fast-relaxed-math", "[cl]") {
    CHECK(buildOptions({"-DA=1", "-DB=2"}) == "-DA=1 -DB=2 -cl-std=CL1.2");
    CHECK_THROWS_AS(buildOptions({"-cl-fast-relaxed-math"}), Error);
}

TEST_CASE("kernel sources: embedded by name, or read from CLRT_KERNEL_DIR", "[cl]") {
    {
        EnvGuard g("CLRT_KERNEL_DIR", nullptr);
        auto srcs = loadKernelSources({"layout.cl"});
        REQUIRE(srcs.size() == 3);  // device_types.h, kernel_params.h, layout.cl
        CHECK(srcs[0].first == "src/shared/device_types.h");
        CHECK(srcs[0].second.rfind("#line 1 \"src/shared/device_types.h\"", 0) == 0);
        CHECK(srcs[1].first == "src/shared/kernel_params.h");
        CHECK(srcs[2].first == "cl_kernels/layout.cl");
        CHECK(srcs[2].second.rfind("#line 1 \"cl_kernels/layout.cl\"", 0) == 0);
        CHECK(srcs[2].second.find("layout_report") != std::string::npos);
        try {
            loadKernelSources({"no_such_kernel.cl"});
            FAIL("missing kernel accepted");
        } catch (const Error& e) {
            CHECK(std::string(e.what()).find("no_such_kernel.cl") != std::string::npos);
            CHECK(std::string(e.what()).find("layout.cl") != std::string::npos);  // lists what is known
        }
    }
    {
        std::string dir = std::string(CLRT_SOURCE_DIR) + "/cl_kernels";
        EnvGuard g("CLRT_KERNEL_DIR", dir.c_str());
        auto srcs = loadKernelSources({"layout.cl"});
        REQUIRE(srcs.size() == 3);
        std::string typesPath = fs::path(dir + "/../src/shared/device_types.h").lexically_normal().string();
        CHECK(srcs[0].first == typesPath);
        CHECK(srcs[0].second == "#line 1 \"" + typesPath + "\"\n" + clrt::test::readFileBytes(typesPath));
        CHECK(srcs[2].first == dir + "/layout.cl");
        // The file's text, with its #include lines turned into comments (same line count).
        std::string expected = "#line 1 \"" + dir + "/layout.cl\"\n" + clrt::test::readFileBytes(dir + "/layout.cl");
        for (std::string header : {"device_types.h", "kernel_params.h"}) {
            const std::string inc = "#include \"../src/shared/" + header + "\"";
            REQUIRE(expected.find(inc) != std::string::npos);
            expected.replace(expected.find(inc), inc.size(),
                             "/* #include \"../src/shared/" + header + "\": placed before this file by the kernel loader */");
        }
        CHECK(srcs[2].second == expected);
        CHECK_THROWS_AS(loadKernelSources({"no_such_kernel.cl"}), Error);
    }
}

namespace {
std::vector<std::string> sourceNames(const std::vector<NamedSource>& srcs) {
    std::vector<std::string> names;
    for (const NamedSource& s : srcs) names.push_back(fs::path(s.first).filename().string());
    return names;
}
}  // namespace

TEST_CASE("kernel sources: each file brings in what it #includes, once, before itself", "[cl]") {
    EnvGuard g("CLRT_KERNEL_DIR", nullptr);
    // The render program: the order the files were concatenated in before they stated their includes
    // (kernel_params.h, macros only, added).
    auto render = loadKernelSources(KernelProgram::Render);
    CHECK(sourceNames(render) == std::vector<std::string>{"device_types.h", "kernel_params.h", "common.cl",
                                                          "intersect.cl", "camera.cl", "textures.cl", "shading_frame.cl",
                                                          "envmap.cl", "object_lights.cl", "lights.cl", "brdf.cl", "material.cl", "path.cl", "shade.cl",
                                                          "compact.cl", "fused.cl", "lanes_math.cl", "lanes_surface.cl",
                                                          "lanes_brdf.cl", "lanes.cl"});
    CHECK(sourceNames(loadKernelSources(KernelProgram::Tonemap)) ==
          std::vector<std::string>{"device_types.h", "kernel_params.h", "tonemap.cl"});
    CHECK(sourceNames(loadKernelSources(KernelProgram::Intersect)) ==
          std::vector<std::string>{"device_types.h", "kernel_params.h", "common.cl", "intersect.cl"});
    CHECK(sourceNames(loadKernelSources({"lights.cl"})) ==
          std::vector<std::string>{"device_types.h", "common.cl", "envmap.cl", "object_lights.cl", "lights.cl"});
    std::regex include(R"((^|\n)[ \t]*#[ \t]*include[ \t]*")");
    for (const NamedSource& s : render) {
        INFO(s.first);
        CHECK_FALSE(std::regex_search(s.second, include));  // the OpenCL compiler resolves no include
    }
    // Every program builds from its roots alone (each file states its dependencies).
    DeviceContext& dc = cpuContext();
    for (KernelProgram p : {KernelProgram::Render, KernelProgram::Tonemap, KernelProgram::Intersect, KernelProgram::Layout})
        CHECK_NOTHROW(buildProgram(dc, p, {}));
    // Each module of cl_kernels/ compiles on its own with what it includes.
    for (auto& e : fs::directory_iterator(std::string(CLRT_SOURCE_DIR) + "/cl_kernels")) {
        INFO(e.path());
        CHECK_NOTHROW(buildProgram(dc, {e.path().filename().string()}, {}));
    }
}

TEST_CASE("kernel sources: a missing #include names the including file and line", "[cl]") {
    fs::path dir = makeTempDir("include");
    fs::create_directories(dir / "cl_kernels");
    {
        std::ofstream(dir / "cl_kernels/a.cl") << "/* a */\n#include \"b.cl\"\n";
        std::ofstream(dir / "cl_kernels/b.cl") << "/* b */\n\n#include \"missing.cl\"\n";
    }
    EnvGuard g("CLRT_KERNEL_DIR", (dir / "cl_kernels").c_str());
    try {
        loadKernelSources({"a.cl"});
        FAIL("missing include accepted");
    } catch (const Error& e) {
        std::string msg = e.what();
        INFO(msg);
        CHECK(e.code() == ExitCode::Device);
        CHECK(msg.find("b.cl:3: #include \"missing.cl\"") != std::string::npos);
    }
    fs::remove_all(dir);
}

TEST_CASE("kernel sources: FP_CONTRACT OFF is scoped to the file that sets it", "[cl]") {
    // A file that turns contraction off turns it back on (the OpenCL default) before it ends, so the
    // files after it in a program compile as they would alone.
    std::regex pragma(R"(#pragma OPENCL FP_CONTRACT (ON|OFF|DEFAULT))");
    for (auto& e : fs::directory_iterator(std::string(CLRT_SOURCE_DIR) + "/cl_kernels")) {
        std::string text = clrt::test::readFileBytes(e.path().string());
        std::string last;
        for (std::sregex_iterator it(text.begin(), text.end(), pragma), end; it != end; ++it) last = (*it)[1].str();
        INFO(e.path());
        CHECK((last.empty() || last == "ON"));
    }
}

TEST_CASE("program cache directory follows the environment", "[cl]") {
    EnvGuard a("CLRT_NO_CACHE", nullptr), b("CLRT_CACHE_DIR", "/tmp/clrt-x"), c("XDG_CACHE_HOME", "/tmp/xdg");
    CHECK(programCacheDir() == "/tmp/clrt-x");
    {
        EnvGuard d("CLRT_CACHE_DIR", nullptr);
        CHECK(programCacheDir() == "/tmp/xdg/clrt");
    }
    EnvGuard e("CLRT_NO_CACHE", "1");
    CHECK(programCacheDir() == "");
}

TEST_CASE("host layout table covers every struct and tiles each one exactly", "[cl][layout]") {
    const auto& table = hostLayout();
    REQUIRE(!table.empty());
    // Every `typedef struct X` of device_types.h has a struct row.
    std::set<std::string> listed;
    for (const LayoutEntry& e : table)
        if (!e.member) listed.insert(e.structName);
    std::string header = clrt::test::readFileBytes(std::string(CLRT_SOURCE_DIR) + "/src/shared/device_types.h");
    std::regex re("typedef\\s+struct\\s+(\\w+)");
    int found = 0;
    for (auto it = std::sregex_iterator(header.begin(), header.end(), re); it != std::sregex_iterator(); ++it) {
        ++found;
        INFO("struct " << (*it)[1].str() << " of device_types.h is missing from cl_kernels/layout.cl");
        CHECK(listed.count((*it)[1].str()) == 1);
    }
    CHECK(found == (int)listed.size());
    // Members (explicit padding included) follow each other without gaps and end at sizeof.
    for (size_t i = 0; i < table.size();) {
        const LayoutEntry& s = table[i];
        REQUIRE(s.member == nullptr);
        CHECK(s.first % 16 == 0);
        int end = 0;
        for (++i; i < table.size() && table[i].member; ++i) {
            INFO(s.structName << "." << table[i].member << ": gap or missing member before it in layout.cl");
            CHECK(table[i].first == end);
            end = table[i].first + table[i].second;
        }
        INFO(s.structName << ": members listed in layout.cl do not reach sizeof");
        CHECK(end == s.first);
    }
}

TEST_CASE("device struct layout matches the host; second build hits the program cache", "[cl][layout]") {
    DeviceContext& dc = cpuContext();
    fs::path dir = makeTempDir("cache");
    EnvGuard noCache("CLRT_NO_CACHE", nullptr);
    EnvGuard kernelDir("CLRT_KERNEL_DIR", nullptr);
    EnvGuard cacheDir("CLRT_CACHE_DIR", dir.c_str());

    BuildInfo first, second;
    std::vector<int> dev1 = deviceLayout(dc, &first);
    CHECK_FALSE(first.cacheHit);
    CHECK(first.seconds > 0);
    CHECK(first.options == buildOptions(dc.quirks().defines));  // "-cl-std=CL1.2" on PoCL (its quirks are host settings, no kernel defines)
    REQUIRE(!first.cacheFile.empty());
    CHECK(fs::exists(first.cacheFile));
    CHECK(fs::path(first.cacheFile).parent_path() == dir);

    std::vector<int> dev2 = deviceLayout(dc, &second);
    CHECK(second.cacheHit);
    CHECK(second.cacheFile == first.cacheFile);
    CHECK(dev2 == dev1);  // the cached binary runs and reports the same

    // Compare entry by entry; a failure names the struct and member.
    const auto& host = hostLayout();
    REQUIRE(dev1.size() == 1 + 2 * host.size());
    CHECK(dev1[0] == (int)host.size());
    for (size_t i = 0; i < host.size(); ++i) {
        const LayoutEntry& e = host[i];
        INFO(e.structName << (e.member ? std::string(".") + e.member : std::string(" (struct)")));
        CHECK(dev1[1 + 2 * i] == e.first);
        CHECK(dev1[2 + 2 * i] == e.second);
    }
    CHECK(layoutMismatches(dev1).empty());

    // layoutMismatches itself reports a difference with the struct and member name.
    std::vector<int> broken = dev1;
    broken[1 + 2 * 1] += 4;  // host[1] is Bvh8Node.planes's offset
    auto diffs = layoutMismatches(broken);
    REQUIRE(diffs.size() == 1);
    CHECK(diffs[0].find(std::string(host[1].structName) + "." + host[1].member) != std::string::npos);

    // A corrupt cache entry falls back to building from source.
    { std::ofstream(first.cacheFile, std::ios::binary | std::ios::trunc) << "garbage"; }
    BuildInfo third;
    std::vector<int> dev3 = deviceLayout(dc, &third);
    CHECK_FALSE(third.cacheHit);
    CHECK(dev3 == dev1);

    std::error_code ec;
    fs::remove_all(dir, ec);
}

TEST_CASE("every kernel has exactly its declared parameters: names, order, address space, const", "[cl]") {
    // The kernels' signatures are generated from src/shared/kernel_params.h and the host binds by the
    // same names; this checks the compiled result (-cl-kernel-arg-info), so a kernel written with a
    // hand-made signature, or a declaration no kernel uses, fails here.
    DeviceContext& dc = cpuContext();
    std::set<std::string> seen;
    // The render program with the lanes kernel's flags (render_lanes exists only in its family's programs).
    const std::vector<std::string> lanes = {"-cl-kernel-arg-info", "-DCLRT_HAS_LANES=1", "-DCLRT_HAS_PATH_TRACING=1",
                                            "-DCLRT_HAS_LIGHT_MESH=1", "-DCLRT_HAS_POINT_LIGHT=1"};
    for (KernelProgram p : {KernelProgram::Render, KernelProgram::Tonemap, KernelProgram::Layout}) {
        cl::Program prog = buildProgram(dc, p, p == KernelProgram::Render ? lanes : std::vector<std::string>{"-cl-kernel-arg-info"});
        size_t n = 0;
        REQUIRE(clGetProgramInfo(prog(), CL_PROGRAM_KERNEL_NAMES, 0, nullptr, &n) == CL_SUCCESS);
        std::string names(n, '\0');
        REQUIRE(clGetProgramInfo(prog(), CL_PROGRAM_KERNEL_NAMES, n, &names[0], nullptr) == CL_SUCCESS);
        names.resize(std::strlen(names.c_str()));
        std::stringstream ss(names);
        for (std::string name; std::getline(ss, name, ';');) {
            INFO("kernel " << name);
            seen.insert(name);
            const KernelDecl& decl = kernelDecl(name);  // throws when undeclared
            KernelArgs args(prog, name.c_str());
            cl::Kernel& k = args.kernel();
            cl_uint numArgs = 0;
            REQUIRE(clGetKernelInfo(k(), CL_KERNEL_NUM_ARGS, sizeof numArgs, &numArgs, nullptr) == CL_SUCCESS);
            REQUIRE(numArgs == decl.params.size());
            for (cl_uint i = 0; i < numArgs; ++i) {
                const ParamDecl& pd = decl.params[i];
                char argName[256] = {};
                REQUIRE(clGetKernelArgInfo(k(), i, CL_KERNEL_ARG_NAME, sizeof argName, argName, nullptr) == CL_SUCCESS);
                CHECK(std::string(argName) == pd.name);
                cl_kernel_arg_address_qualifier aq = 0;
                REQUIRE(clGetKernelArgInfo(k(), i, CL_KERNEL_ARG_ADDRESS_QUALIFIER, sizeof aq, &aq, nullptr) == CL_SUCCESS);
                CHECK(aq == (pd.kind == ParamKind::VAL ? CL_KERNEL_ARG_ADDRESS_PRIVATE : CL_KERNEL_ARG_ADDRESS_GLOBAL));
                cl_kernel_arg_type_qualifier tq = 0;
                REQUIRE(clGetKernelArgInfo(k(), i, CL_KERNEL_ARG_TYPE_QUALIFIER, sizeof tq, &tq, nullptr) == CL_SUCCESS);
                if (pd.kind != ParamKind::VAL) CHECK(((tq & CL_KERNEL_ARG_TYPE_CONST) != 0) == (pd.kind == ParamKind::IN));
            }
        }
    }
    for (const KernelDecl& d : kernelDecls()) CHECK(seen.count(d.name) == 1);
}

TEST_CASE("KernelArgs refuses a wrong binding before any launch", "[cl]") {
    DeviceContext& dc = cpuContext();
    cl::Program prog = buildProgram(dc, KernelProgram::Render, {});
    KernelArgs k(prog, "gather_shadows");
    cl::Buffer b = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_WRITE, 64));
    auto throwsWith = [](auto f, const std::string& what) {
        try {
            f();
        } catch (const Error& e) {
            INFO(e.what());
            CHECK(std::string(e.what()).find(what) != std::string::npos);
            CHECK(e.code() == ExitCode::Device);
            return;
        }
        FAIL("no error for: " << what);
    };
    throwsWith([&] { k.set("nope", b); }, "kernel gather_shadows has no parameter nope");
    throwsWith([&] { k.set("chunk", b); }, "parameter chunk is a value; a buffer was bound");
    throwsWith([&] { k.set("shadows", 3); }, "parameter shadows is a buffer; a value was bound");
    throwsWith([&] { k.set("chunk", size_t(3)); }, "parameter chunk takes 4 bytes; 8 were bound");
    k.set("queueCount", b).set("chunk", 1).set("shadows", b);
    throwsWith([&] { k.ready(); }, "parameter pathRadiance is not bound");
    k.set("pathRadiance", b);
    CHECK_NOTHROW(k.ready());
    CHECK_THROWS_AS(KernelArgs(prog, "no_such_kernel"), Error);
}

TEST_CASE("type tables: every light, material and BRDF row has its device case under its feature flag", "[cl]") {
    // README "Adding a light or a material": a table row in device_types.h, a `case` in the device
    // dispatcher inside `#ifdef` the row's flag. Checked on the sources: a row without device code
    // (or device code under another flag) fails here, not as a silently black light.
    const std::string lights = clrt::test::readFileBytes(std::string(CLRT_SOURCE_DIR) + "/cl_kernels/lights.cl");
    const std::string shade = clrt::test::readFileBytes(std::string(CLRT_SOURCE_DIR) + "/cl_kernels/shade.cl");
    const std::string brdf = clrt::test::readFileBytes(std::string(CLRT_SOURCE_DIR) + "/cl_kernels/brdf.cl");
    // The flag guarding `case K:` is the nearest #ifdef before it, closed by an #endif after it.
    auto guardOf = [](const std::string& text, const std::string& constant) -> std::string {
        size_t at = text.find("case " + constant + ":");
        if (at == std::string::npos) return "(no case)";
        size_t ifdef = text.rfind("#ifdef ", at), endif = text.rfind("#endif", at);
        if (ifdef == std::string::npos || (endif != std::string::npos && endif > ifdef)) return "";
        size_t end = text.find_first_of(" \n", ifdef + 7);
        return text.substr(ifdef + 7, end - ifdef - 7);
    };
    for (const auto& row : lightTypes()) {
        INFO("light " << row.constant);
        CHECK(guardOf(lights, row.constant) == row.flag);
    }
    for (const auto& row : materialTypes()) {
        INFO("material " << row.constant);
        if (*row.flag) CHECK(guardOf(shade, row.constant) == row.flag);
        // Materials that spawn children are those shade_hits writes children for.
        if (row.bounces) CHECK(guardOf(shade, row.constant) != "(no case)");
    }
    // BRDFs: the first `case` of each row is Brdf_Eval's, under the row's flag.
    for (const auto& row : brdfTypes()) {
        INFO("BRDF " << row.constant);
        CHECK(guardOf(brdf, row.constant) == row.flag);
    }
    // Every flag a scene can ask for is one FeatureSet::all() sets.
    std::vector<std::string> all = FeatureSet::all().defines();
    for (const auto& row : lightTypes())
        CHECK(std::find(all.begin(), all.end(), std::string("-D") + row.flag + "=1") != all.end());
    for (const auto& row : brdfTypes())
        CHECK(std::find(all.begin(), all.end(), std::string("-D") + row.flag + "=1") != all.end());
}
