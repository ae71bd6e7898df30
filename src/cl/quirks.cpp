// quirks.cpp — the quirk table and the detection of a device's implementation (see quirks.h and
// docs/quirks.md, which describes every row and how to add one). Reads no scene element.
#include "cl/quirks.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include "cl/devices.h"
#include "util/error.h"

namespace clrt {

namespace {

std::string lowered(std::string s) {
    for (char& c : s) c = char(std::tolower((unsigned char)c));
    return s;
}

bool has(const std::string& lowerText, const char* part) { return lowerText.find(part) != std::string::npos; }

void fixedWorkGroup64(HostSettings& h) { h.workGroupSize = 64; }
void buildOnContextThread(HostSettings& h) { h.buildOnContextThread = true; }

}  // namespace

unsigned detectImplementation(const std::string& platformName, const std::string& deviceVendor) {
    const std::string p = lowered(platformName), v = lowered(deviceVendor);
    if (has(p, "portable computing language") || has(p, "pocl")) return kImplPocl;
    if (has(p, "oclgrind")) return kImplOclgrind;
    if (has(p, "rusticl") || has(p, "clover") || has(p, "mesa")) return kImplMesa;
    if (has(p, "intel")) return has(p, "graphics") ? kImplIntelGpu : kImplIntelCpu;
    if (has(p, "nvidia")) return kImplNvidia;
    if (has(p, "amd") || has(p, "advanced micro devices")) return kImplAmd;
    if (has(p, "apple")) return kImplApple;
    // A platform name not seen before: the device vendor, for the GPU vendors' own runtimes only.
    if (has(v, "nvidia")) return kImplNvidia;
    if (has(v, "advanced micro devices") || v == "amd") return kImplAmd;
    return kImplOther;
}

const char* implementationName(unsigned implementationBit) {
    switch (implementationBit) {
    case kImplPocl: return "PoCL";
    case kImplIntelCpu: return "Intel CPU runtime";
    case kImplIntelGpu: return "Intel GPU runtime";
    case kImplNvidia: return "NVIDIA";
    case kImplAmd: return "AMD";
    case kImplApple: return "Apple";
    case kImplMesa: return "Mesa";
    case kImplOclgrind: return "Oclgrind";
    default: return "other";
    }
}

const std::vector<Quirk>& quirkTable() {
    // docs/quirks.md has the evidence of each row; keep the two in step.
    static const std::vector<Quirk> table = {
        {"INTEL_VEC_HINT", kImplIntelCpu, CL_DEVICE_TYPE_ALL, true,
         "the implicit work-item vectoriser of Intel's CPU runtime (2026.22) miscompiles shade_hits (children "
         "holding other work-items' values: classic/veachAjar's glass teapot wrong on ~1.5% of pixels, issue 17) "
         "and runs the divergent render_fused 2.1x slower; vec_type_hint(float4) on both kernels "
         "(CLRT_KERNEL_VEC_HINT) keeps it from vectorising them",
         "scripts/intel_vectorizer_repro.sh (renders and tests/intel_repro/shade_hits_alone.cpp); "
         "tests/test_implementations.cpp [impl][conformance]",
         nullptr},
        {"FIXED_WORK_GROUP", kImplAll, CL_DEVICE_TYPE_ALL, false,
         "PoCL compiles a kernel once per distinct local size, and a runtime-chosen one varies with the global "
         "size (a recompile at every queue length); every implementation gets the fixed 64 that every device "
         "ran with before this table (the tone mapper's partial sums follow the work-item count, so its bytes "
         "would change with another size)",
         "tests/test_quirks.cpp [quirks] (every implementation gets 64); "
         "CLRT_QUIRKS=-FIXED_WORK_GROUP clrt render ... --device cpu shows PoCL's recompiles in the render time",
         fixedWorkGroup64},
        {"BUILD_ON_CONTEXT_THREAD", kImplOclgrind, CL_DEVICE_TYPE_ALL, false,
         "oclgrind 21.10 with its uninitialised-value plugin (OCLGRIND_UNINITIALIZED) crashes (SIGSEGV in "
         "MemoryPool::alloc from ShadowContext::getCleanValue, under clBuildProgram's allocateProgramScopeVars) "
         "when a program is built on a thread other than the one that made the context: clrt render's early "
         "build, overlapping the flattening, runs on the context's thread there",
         "scripts/oclgrind_suite.sh's uninit pass (every render exits 139 with CLRT_QUIRKS=-BUILD_ON_CONTEXT_THREAD)",
         buildOnContextThread},
        {"BIT_REVERSE_TABLE", kImplOclgrind, CL_DEVICE_TYPE_ALL, true,
         "oclgrind 21.10 cannot run the llvm.bitreverse intrinsic (\"Undefined external function\"), which LLVM "
         "makes of Bits_Reverse's shift-and-mask network (common.cl); there the bits are reversed by a table of "
         "reversed bytes (CLRT_BITS_REVERSE_BY_TABLE), the same values",
         "scripts/oclgrind_suite.sh (its renders fail with CLRT_QUIRKS=-BIT_REVERSE_TABLE); tests/test_sampler.cpp "
         "[sampler][cl][quirks] checks both forms against the host's reversal",
         nullptr},
    };
    return table;
}

namespace {

const Quirk* findQuirk(const std::string& name) {
    for (const Quirk& q : quirkTable())
        if (name == q.name) return &q;
    return nullptr;
}

std::string knownQuirks() {
    std::string s;
    for (const Quirk& q : quirkTable()) s += std::string(s.empty() ? "" : ", ") + q.name;
    return s;
}

// Applies the $CLRT_QUIRKS syntax to `on` (one flag per table row).
void applyOverrides(const std::string& overrides, std::vector<bool>& on) {
    const std::vector<Quirk>& table = quirkTable();
    size_t pos = 0;
    while (pos <= overrides.size()) {
        size_t end = overrides.find(',', pos);
        if (end == std::string::npos) end = overrides.size();
        std::string item = overrides.substr(pos, end - pos);
        pos = end + 1;
        item.erase(std::remove_if(item.begin(), item.end(), [](char c) { return std::isspace((unsigned char)c); }),
                   item.end());
        if (item.empty()) continue;
        if (item == "none") {
            std::fill(on.begin(), on.end(), false);
            continue;
        }
        const bool add = item[0] != '-';
        if (item[0] == '-' || item[0] == '+') item.erase(0, 1);
        const Quirk* q = findQuirk(item);
        if (!q)
            throw Error("CLRT_QUIRKS: unknown quirk \"" + item + "\" (known: " + knownQuirks() + ", or none)",
                        ExitCode::Usage);
        on[size_t(q - table.data())] = add;
    }
}

}  // namespace

DeviceQuirks quirksFor(unsigned implementation, cl_device_type type, const std::string& overrides) {
    const std::vector<Quirk>& table = quirkTable();
    std::vector<bool> on(table.size());
    for (size_t i = 0; i < table.size(); ++i)
        on[i] = (table[i].implementations & implementation) != 0 && (table[i].deviceTypes & type) != 0;
    applyOverrides(overrides, on);
    DeviceQuirks dq;
    dq.implementation = implementation;
    for (size_t i = 0; i < table.size(); ++i) {
        if (!on[i]) continue;
        dq.names.push_back(table[i].name);
        if (table[i].kernelDefine) dq.defines.push_back(std::string("-DCLRT_QUIRK_") + table[i].name);
        if (table[i].host) table[i].host(dq.host);
    }
    return dq;
}

DeviceQuirks deviceQuirks(const DeviceInfo& device) {
    const char* env = std::getenv("CLRT_QUIRKS");
    return quirksFor(detectImplementation(device.platformName, device.vendor), device.type, env ? env : "");
}

}  // namespace clrt
