// test_quirks.cpp — device quirks (src/cl/quirks.h, docs/quirks.md): sample platform and vendor strings
// map to the right implementation, each implementation gets the right -DCLRT_QUIRK_* defines and host
// settings, $CLRT_QUIRKS overrides parse, and a program built on the test device (PoCL by default)
// is compiled with that device's defines and sees them (a probe kernel writes whether a macro is set).
#include <catch.hpp>

#include <CL/opencl.hpp>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

#include "cl/check.h"
#include "cl/kernel_args.h"
#include "cl/program.h"
#include "cl/quirks.h"
#include "test_helpers.h"
#include "util/error.h"

using namespace clrt;

namespace {

using Strings = std::vector<std::string>;

bool hasQuirk(const DeviceQuirks& q, const std::string& name) {
    for (const std::string& n : q.names)
        if (n == name) return true;
    return false;
}

// Builds a probe kernel (with common.cl, so CLRT_KERNEL_VEC_HINT is defined as the device's quirks
// say) on dc; returns whether CLRT_QUIRK_INTEL_VEC_HINT was defined, and the build's info in *bi.
int probeIntelVecHint(DeviceContext& dc, BuildInfo* bi) {
    static const char* src = R"CLC(
__kernel CLRT_KERNEL_VEC_HINT void quirk_probe(__global int* out) {
#ifdef CLRT_QUIRK_INTEL_VEC_HINT
    out[get_global_id(0)] = 1;
#else
    out[get_global_id(0)] = 0;
#endif
}
)CLC";
    std::vector<NamedSource> sources = loadKernelSources({"common.cl"});
    sources.push_back({"quirk_probe.cl", src});
    cl::Program program = buildProgramFromSources(dc, sources, {"-DCLRT_TEST_PROBE=1"}, bi);
    cl::Kernel k = CL_CPP(cl::Kernel(program, "quirk_probe"));
    cl::Buffer out = CL_CPP(cl::Buffer(dc.context(), CL_MEM_READ_WRITE, sizeof(cl_int)));
    CL_CHECK(clSetKernelArg(k(), 0, sizeof(cl_mem), &out()));
    CL_CPP(dc.queue().enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(1), cl::NullRange));
    cl_int v = -1;
    CL_CPP(dc.queue().enqueueReadBuffer(out, CL_TRUE, 0, sizeof v, &v));
    return v;
}

}  // namespace

TEST_CASE("Quirks: platform and vendor strings map to implementations", "[quirks]") {
    CHECK(detectImplementation("Portable Computing Language", "GenuineIntel") == kImplPocl);  // PoCL on an Intel CPU
    CHECK(detectImplementation("Portable Computing Language", "AuthenticAMD") == kImplPocl);
    CHECK(detectImplementation("Intel(R) OpenCL", "Intel(R) Corporation") == kImplIntelCpu);
    CHECK(detectImplementation("Intel(R) CPU Runtime for OpenCL(TM) Applications", "Intel(R) Corporation") ==
          kImplIntelCpu);
    CHECK(detectImplementation("Intel(R) FPGA Emulation Platform for OpenCL(TM)", "Intel(R) Corporation") ==
          kImplIntelCpu);
    CHECK(detectImplementation("Intel(R) OpenCL Graphics", "Intel(R) Corporation") == kImplIntelGpu);
    CHECK(detectImplementation("Intel(R) OpenCL HD Graphics", "Intel(R) Corporation") == kImplIntelGpu);
    CHECK(detectImplementation("NVIDIA CUDA", "NVIDIA Corporation") == kImplNvidia);
    CHECK(detectImplementation("AMD Accelerated Parallel Processing", "Advanced Micro Devices, Inc.") == kImplAmd);
    CHECK(detectImplementation("rusticl", "AMD") == kImplMesa);  // Mesa's runtime on an AMD GPU: not AMD's
    CHECK(detectImplementation("Clover", "AMD") == kImplMesa);
    CHECK(detectImplementation("Apple", "Apple") == kImplApple);
    CHECK(detectImplementation("Oclgrind", "University of Bristol") == kImplOclgrind);
    CHECK(detectImplementation("Some New Platform", "NVIDIA Corporation") == kImplNvidia);
    CHECK(detectImplementation("Some New Platform", "Acme") == kImplOther);
    CHECK(std::string(implementationName(kImplPocl)) == "PoCL");
    CHECK(std::string(implementationName(kImplOther)) == "other");
}

TEST_CASE("Quirks: each implementation gets its defines and host settings", "[quirks]") {
    const Strings intel = {"-DCLRT_QUIRK_INTEL_VEC_HINT"};
    CHECK(quirksFor(kImplIntelCpu, CL_DEVICE_TYPE_CPU).defines == intel);
    CHECK(quirksFor(kImplIntelCpu, CL_DEVICE_TYPE_ACCELERATOR).defines == intel);  // FPGA emulation: same compiler
    // Oclgrind: the byte table for bit reversal (it cannot run llvm.bitreverse).
    const Strings oclgrind = {"-DCLRT_QUIRK_BIT_REVERSE_TABLE"};
    CHECK(quirksFor(kImplOclgrind, CL_DEVICE_TYPE_CPU).defines == oclgrind);
    CHECK(quirksFor(kImplOclgrind, CL_DEVICE_TYPE_GPU).defines == oclgrind);
    // Everyone else: no kernel define (PoCL's programs are built exactly as before the table; GPU
    // targets too, which scripts/gpu_compile_check.sh relies on).
    for (unsigned impl : {kImplPocl, kImplIntelGpu, kImplNvidia, kImplAmd, kImplApple, kImplMesa, kImplOther})
        for (cl_device_type type : {CL_DEVICE_TYPE_CPU, CL_DEVICE_TYPE_GPU}) {
            INFO(implementationName(impl) << " type " << type);
            CHECK(quirksFor(impl, type).defines.empty());
        }
    // The fixed work-group size of 64: every implementation, every device type (as before the table).
    for (unsigned bit = 1; bit <= kImplOther; bit <<= 1)
        for (cl_device_type type : {CL_DEVICE_TYPE_CPU, CL_DEVICE_TYPE_GPU, CL_DEVICE_TYPE_ACCELERATOR}) {
            INFO(implementationName(bit) << " type " << type);
            const DeviceQuirks q = quirksFor(bit, type);
            CHECK(q.implementation == bit);
            CHECK(q.host.workGroupSize == 64);
            CHECK(hasQuirk(q, "FIXED_WORK_GROUP"));
            // Programs built on the context's thread only: Oclgrind alone (its uninit plugin crashes
            // otherwise); everyone else may build while the scene is flattened.
            CHECK(q.host.buildOnContextThread == (bit == kImplOclgrind));
            CHECK(hasQuirk(q, "BUILD_ON_CONTEXT_THREAD") == (bit == kImplOclgrind));
        }
}

TEST_CASE("Quirks: the table's rows are complete and $CLRT_QUIRKS overrides parse", "[quirks]") {
    std::vector<std::string> seen;
    for (const Quirk& q : quirkTable()) {
        INFO(q.name);
        const std::string name = q.name;
        CHECK(!name.empty());
        CHECK(name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_") == std::string::npos);
        CHECK(std::find(seen.begin(), seen.end(), name) == seen.end());
        seen.push_back(name);
        CHECK(q.implementations != 0);
        CHECK((q.implementations & ~unsigned(kImplAll)) == 0);
        CHECK(std::string(q.defect).size() > 20);
        CHECK(std::string(q.reproducer).size() > 10);
        CHECK((q.kernelDefine || q.host));  // a row does something
    }
    CHECK(quirksFor(kImplIntelCpu, CL_DEVICE_TYPE_CPU, "-INTEL_VEC_HINT").defines.empty());
    CHECK(quirksFor(kImplPocl, CL_DEVICE_TYPE_CPU, "+INTEL_VEC_HINT").defines == Strings{"-DCLRT_QUIRK_INTEL_VEC_HINT"});
    CHECK(quirksFor(kImplPocl, CL_DEVICE_TYPE_CPU, " INTEL_VEC_HINT , ").defines.size() == 1);
    const DeviceQuirks none = quirksFor(kImplIntelCpu, CL_DEVICE_TYPE_CPU, "none");
    CHECK(none.names.empty());
    CHECK(none.host.workGroupSize == 0);  // the runtime's choice
    CHECK(quirksFor(kImplPocl, CL_DEVICE_TYPE_CPU, "none,+FIXED_WORK_GROUP").host.workGroupSize == 64);
    try {
        quirksFor(kImplPocl, CL_DEVICE_TYPE_CPU, "-NO_SUCH_QUIRK");
        FAIL("no throw");
    } catch (const Error& e) {
        CHECK(e.code() == ExitCode::Usage);
        CHECK(std::string(e.what()).find("INTEL_VEC_HINT") != std::string::npos);  // lists the known ones
    }
}

TEST_CASE("Quirks: a program built on the device gets the device's defines", "[quirks][cl]") {
    DeviceContext& dc = test::testContext();
    const DeviceInfo& di = dc.info();
    const unsigned impl = detectImplementation(di.platformName, di.vendor);
    CHECK(dc.quirks().implementation == impl);
    if (!std::getenv("CLRT_QUIRKS") && impl == kImplPocl) CHECK(dc.quirks().defines.empty());
    BuildInfo plain;
    const int defined = probeIntelVecHint(dc, &plain);
    CHECK(defined == (hasQuirk(dc.quirks(), "INTEL_VEC_HINT") ? 1 : 0));
    for (const std::string& d : dc.quirks().defines) CHECK(plain.options.find(d) != std::string::npos);
    CHECK(plain.options.rfind("-DCLRT_TEST_PROBE=1 ", 0) == 0);  // the caller's defines first

    // The same device with the quirk forced on through $CLRT_QUIRKS: the macro is seen, the options
    // (and so the binary-cache key) differ.
    const char* old = std::getenv("CLRT_QUIRKS");
    const std::string saved = old ? old : "";
    setenv("CLRT_QUIRKS", "+INTEL_VEC_HINT", 1);
    DeviceContext forced(di);
    if (old) setenv("CLRT_QUIRKS", saved.c_str(), 1);
    else unsetenv("CLRT_QUIRKS");
    BuildInfo withHint;
    CHECK(probeIntelVecHint(forced, &withHint) == 1);
    CHECK(withHint.options.find("-DCLRT_QUIRK_INTEL_VEC_HINT") != std::string::npos);
    if (defined == 0) {
        CHECK(withHint.options != plain.options);
        if (!plain.cacheFile.empty()) CHECK(withHint.cacheFile != plain.cacheFile);
    }
}
