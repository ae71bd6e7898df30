// test_memory.cpp — the memory estimate (flatten/memory_estimate.h) against the arrays a real
// flattening makes on shared and own scenes, and the out-of-memory refusal through the binary:
// a small --max-memory cap, and a scene that would need terabytes, refused in seconds with one line.
#include <catch.hpp>

#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>

#include "flatten/memory_estimate.h"
#include "scene/scene_loader.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

template <class V> uint64_t bytesOf(const V& v) { return uint64_t(v.size()) * sizeof(typename V::value_type); }

// The device arrays of a flattened scene by the estimate's families.
struct Actual {
    uint64_t geometry, bvh, textures, lights;
    uint64_t total() const { return geometry + bvh + textures + lights; }
};
Actual actualBytes(const DeviceScene& ds) {
    Actual a{};
    a.geometry = bytesOf(ds.triangles) + bytesOf(ds.triangleShading) + bytesOf(ds.triangleAttributes) + bytesOf(ds.spheres) + bytesOf(ds.planes);
    a.bvh = bytesOf(ds.bvh8.nodes) + bytesOf(ds.bvh8.leaves);
    a.textures = bytesOf(ds.texels);
    a.lights = bytesOf(ds.lights) + bytesOf(ds.lightData) + bytesOf(ds.envDistribution);
    return a;
}

// A binary PLY height field of 2·n·n triangles over [0,1]², z a few bumps.
void writeHeightField(const std::string& path, int n) {
    std::ofstream f(path, std::ios::binary);
    const int v = n + 1;
    f << "ply\nformat binary_little_endian 1.0\nelement vertex " << v * v
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << 2 * n * n
      << "\nproperty list uchar int vertex_indices\nend_header\n";
    for (int j = 0; j < v; ++j)
        for (int i = 0; i < v; ++i) {
            float p[3] = {float(i) / n, float(j) / n, 0.05f * float((i * 7 + j * 3) % 5)};
            f.write(reinterpret_cast<const char*>(p), sizeof p);
        }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const int a = j * v + i, b = a + 1, c = a + v, d = c + 1;
            const int tris[2][3] = {{a, b, d}, {a, d, c}};
            for (const auto& t : tris) {
                const unsigned char three = 3;
                f.write(reinterpret_cast<const char*>(&three), 1);
                f.write(reinterpret_cast<const char*>(t), sizeof t);
            }
        }
}

// A scene placing ply `plyName` `instances` times (the first as a Mesh, the rest as MeshInstances).
std::string instancedScene(const std::string& plyName, int instances) {
    std::ostringstream s;
    s << "<Scene><Cameras><Camera id=\"1\"><Position>0.5 0.5 3</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up>"
         "<NearPlane>-1 1 -1 1</NearPlane><NearDistance>1</NearDistance><ImageResolution>8 8</ImageResolution>"
         "<ImageName>out.png</ImageName></Camera></Cameras>"
         "<Lights><AmbientLight>20 20 20</AmbientLight><PointLight id=\"1\"><Position>0 0 5</Position>"
         "<Intensity>100 100 100</Intensity></PointLight></Lights>"
         "<Materials><Material id=\"1\"><DiffuseReflectance>1 1 1</DiffuseReflectance></Material></Materials>"
         "<Transformations><Translation id=\"1\">0.001 0 0</Translation></Transformations>"
         "<Objects><Mesh id=\"1\"><Material>1</Material><Faces plyFile=\"" << plyName << "\"/></Mesh>";
    for (int i = 2; i <= instances; ++i)
        s << "<MeshInstance id=\"" << i << "\" baseMeshId=\"" << i - 1 << "\"><Transformations>t1</Transformations></MeshInstance>";
    s << "</Objects></Scene>";
    return s.str();
}

void checkEstimate(const Scene& scene, const std::string& name, Instancing instancing = Instancing::Auto) {
    MemoryPlan plan;  // as clrt render makes it
    const std::vector<bool> instanced = instancedShapes(scene, instancing);
    plan.meshInstanced.assign(scene.meshes.size(), false);
    for (size_t i = 0; i < scene.shapes.size(); ++i)
        if (instanced[i]) plan.meshInstanced[size_t(scene.shapes[i].meshIndex)] = true;
    const MemoryEstimate e = estimateMemory(scene, plan);
    FlattenOptions opts;
    opts.instancing = instancing;
    const DeviceScene ds = flattenScene(scene, opts);
    const Actual a = actualBytes(ds);
    INFO(name << ": estimate geometry " << e.geometry.bytes << " bvh " << e.bvh.bytes << " textures "
              << e.textures.bytes << " lights " << e.lights.bytes << " (total " << e.deviceScene() << "); actual "
              << a.geometry << " / " << a.bvh << " / " << a.textures << " / " << a.lights << " (total " << a.total()
              << ")");
    // Each family: never under by more than 5%, never over by more than 2x (+64 KB for tiny scenes).
    const uint64_t est[4] = {e.geometry.bytes, e.bvh.bytes, e.textures.bytes, e.lights.bytes};
    const uint64_t act[4] = {a.geometry, a.bvh, a.textures, a.lights};
    for (int k = 0; k < 4; ++k) {
        INFO("family " << k);
        CHECK(double(est[k]) >= 0.95 * double(act[k]));
        CHECK(est[k] <= 2 * act[k] + (64u << 10));
    }
    CHECK(e.trianglesStored == uint64_t(ds.params.numTriangles) + ds.skippedTriangles);
    CHECK(e.instances == uint64_t(ds.params.numInstances));
}

}  // namespace

TEST_CASE("memory: flattening lends the BVH builder's freed scratch to the 8-wide nodes and leaf blocks", "[memory][huge_pages]") {
    TempDir d;
    writeHeightField(d.file("field.ply"), 200);  // 80,000 triangles: every array below is >= 1 MiB
    writeFileBytes(d.file("one.xml"), instancedScene("field.ply", 1));
    const Scene scene = loadScene(d.file("one.xml"));
    for (Instancing mode : {Instancing::Flatten, Instancing::TwoLevel}) {
        INFO("instancing " << int(mode));
        const size_t before = hugeRecycledBytes();
        FlattenOptions opts;
        opts.instancing = mode;
        DeviceScene ds = flattenScene(scene, opts);
        // The builder's items (32 B per triangle) hold the 8-wide nodes, its binary nodes the leaf blocks.
        const size_t nodes = ds.bvh8.nodes.size() * sizeof(dev::Bvh8Node), leaves = ds.bvh8.leaves.size() * sizeof(dev::LeafBlock);
        REQUIRE(nodes >= kHugeMinBytes);
        REQUIRE(leaves >= kHugeMinBytes);
        CHECK(hugeRecycledBytes() - before >= nodes + leaves);
        CHECK(hugeKeptBytes() == 0);  // nothing kept past flattenScene
    }
}

TEST_CASE("memory: the estimate against the arrays of a real flattening", "[memory]") {
    TempDir d;
    writeHeightField(d.file("field.ply"), 200);  // 80,000 triangles
    writeFileBytes(d.file("one.xml"), instancedScene("field.ply", 1));
    writeFileBytes(d.file("four.xml"), instancedScene("field.ply", 4));
    checkEstimate(loadScene(d.file("one.xml")), "height field");
    checkEstimate(loadScene(d.file("four.xml")), "4 instances of the height field");
    checkEstimate(loadScene(d.file("one.xml")), "height field, two-level", Instancing::TwoLevel);
    checkEstimate(loadScene(d.file("four.xml")), "4 instances of the height field, two-level", Instancing::TwoLevel);
    if (!haveShared()) return;
    for (const char* s : {"hw1/bunny.xml", "hw2/grass/grass_desert.xml", "hw5/head_env_light_courtyard.xml",
                          "hw4/brickwall_with_normalmap.xml", "hw5/tt/scene_pisa_courtyard.xml"}) {
        const std::string path = sharedDir() + "/scenes/" + s;
        if (!std::ifstream(path)) continue;
        checkEstimate(loadScene(path), s);
    }
    const std::string grass = sharedDir() + "/scenes/hw2/grass/grass_desert.xml";  // 13 placements of grass meshes
    if (std::ifstream(grass)) checkEstimate(loadScene(grass), "grass_desert, two-level", Instancing::TwoLevel);
}

TEST_CASE("memory: the host peak estimate against the peak RSS of a render", "[memory][cli]") {
    // Calibration (PoCL, the 2-core VM, /usr/bin/time), with the scene arrays used in place (session 14):
    // height fields of 320k triangles 183 MB estimated / 182 MB measured, 4M 1.4 / 1.25 GB; every array
    // copied (CLRT_HUGE_PAGES=0) 320k 256 / 247 MB. Session 15 (binary tree freed before the leaf blocks,
    // clrt -v): 320k 179.0 / 167.6 MB (before: 190.6 / 176.4), 1M 345.7 / 341.0 MB, 4M 1.1 / 1.07 GB.
    TempDir d;
    writeHeightField(d.file("field.ply"), 400);  // 320,000 triangles
    writeFileBytes(d.file("s.xml"), instancedScene("field.ply", 1));
    // The system's OpenCL ICDs only: scripts/test.sh also registers Intel's CPU runtime
    // (build/opencl-env.sh), whose library holds more after the memory check than at it (295 MB peak
    // against a 270 MB estimate), memory the estimate does not see (a known gap: docs/architecture.md).
    // The peak is clrt's own VmHWM (its -v line): the ru_maxrss of a child forked from this test process
    // counts this process's image too (as large as 433 MB late in the suite).
    const std::string env = std::filesystem::exists("/etc/OpenCL/vendors") ? "OCL_ICD_VENDORS=/etc/OpenCL/vendors " : "";
    const std::string base = env + std::string(CLRT_BINARY) + " render " + d.file("s.xml") + " -o " + d.path.string() + deviceArg();
    // The estimate (-v's line, printed before the refusal) and clrt's own peak of a render, in MB.
    auto measure = [&](const std::string& args, double& estimateMb, double& measuredMb) {
        const int refused = std::system((base + args + " -v --max-memory 1K >" + d.file("log") + " 2>&1").c_str());
        REQUIRE((WIFEXITED(refused) && WEXITSTATUS(refused) == 2));
        const std::string log = readFileBytes(d.file("log"));
        const size_t at = log.find("host peak ");
        REQUIRE(at != std::string::npos);
        estimateMb = std::stod(log.substr(at + 10));
        REQUIRE(log.compare(log.find(' ', at + 10), 4, " MB,") == 0);
        REQUIRE(std::system((base + args + " >/dev/null 2>&1").c_str()) == 0);  // warms the kernel cache
        REQUIRE(std::system((base + args + " -v >" + d.file("run.log") + " 2>&1").c_str()) == 0);
        const std::string runLog = readFileBytes(d.file("run.log"));
        const size_t peakAt = runLog.rfind("memory: peak resident ");
        REQUIRE(peakAt != std::string::npos);
        measuredMb = std::stod(runLog.substr(peakAt + 22));
    };
    double estimateMb = 0, measuredMb = 0;
    measure("", estimateMb, measuredMb);
    INFO("flattened: estimate " << estimateMb << " MB, measured " << measuredMb << " MB");
    CHECK(estimateMb >= 0.9 * measuredMb);
    CHECK(estimateMb <= 1.25 * measuredMb);
    // The same mesh as one instance of a two-level BVH (session 16: its bottom level is built in place as
    // the world tree is; before, 1M triangles peaked at 613 MB against 348 MB flattened): issue 30's goal,
    // 100 placements within 1.2x of one flattened mesh, starts with one placement costing no more.
    double estimateTwoLevelMb = 0, measuredTwoLevelMb = 0;
    measure(" --instancing two-level", estimateTwoLevelMb, measuredTwoLevelMb);
    INFO("two-level: estimate " << estimateTwoLevelMb << " MB, measured " << measuredTwoLevelMb << " MB");
    CHECK(estimateTwoLevelMb >= 0.9 * measuredTwoLevelMb);
    CHECK(estimateTwoLevelMb <= 1.25 * measuredTwoLevelMb);
    CHECK(measuredTwoLevelMb <= 1.1 * measuredMb);
}

TEST_CASE("memory: a mesh marked instanced counts its triangles once", "[memory]") {
    TempDir d;
    writeHeightField(d.file("field.ply"), 50);  // 5,000 triangles
    writeFileBytes(d.file("s.xml"), instancedScene("field.ply", 100));
    const Scene scene = loadScene(d.file("s.xml"));
    MemoryPlan flat, twoLevel;
    twoLevel.meshInstanced.assign(scene.meshes.size(), true);
    const MemoryEstimate f = estimateMemory(scene, flat), t = estimateMemory(scene, twoLevel);
    CHECK(f.trianglesSeen == 500000);
    CHECK(f.trianglesStored == 500000);
    CHECK(t.trianglesSeen == 500000);
    CHECK(t.trianglesStored == 5000);
    CHECK(t.instances == 100);
    CHECK(t.deviceScene() * 20 < f.deviceScene());
}

TEST_CASE("memory: sizes parse and print in powers of 1024", "[memory]") {
    uint64_t b = 0;
    CHECK((parseByteSize("512M", b) && b == (uint64_t(512) << 20)));
    CHECK((parseByteSize("4G", b) && b == (uint64_t(4) << 30)));
    CHECK((parseByteSize("1.5T", b) && b == (uint64_t(3) << 39)));
    CHECK((parseByteSize("2kB", b) && b == 2048));
    CHECK((parseByteSize("1000", b) && b == 1000));
    CHECK_FALSE(parseByteSize("", b));
    CHECK_FALSE(parseByteSize("0", b));
    CHECK_FALSE(parseByteSize("4X", b));
    CHECK_FALSE(parseByteSize("-1G", b));
    CHECK_FALSE(parseByteSize("G", b));
    CHECK(formatBytes(512) == "512 B");
    CHECK(formatBytes(uint64_t(3) << 29) == "1.5 GB");
    CHECK(availableHostMemory() > 0);
    CHECK(residentBytes() > 0);
}

TEST_CASE("memory: a scene over --max-memory exits 2 with one line, before flattening", "[memory][cli]") {
    TempDir d;
    writeHeightField(d.file("field.ply"), 100);  // 20,000 triangles: about 10 MB flattened
    writeFileBytes(d.file("s.xml"), instancedScene("field.ply", 2));
    const std::string base = "render " + d.file("s.xml") + " -o " + d.path.string() + deviceArg();
    auto run = [&](const std::string& args) {
        const int rc = runClrt(args, d.file("log"));  // before the log is read
        return cliResult(rc, readFileBytes(d.file("log")));
    };
    CliResult r = run(base + " --max-memory 4M");
    INFO(r.log);
    CHECK(r.rc == 2);
    CHECK(r.errorLines == 1);
    CHECK(r.errorLine.find("needs ") != std::string::npos);
    CHECK(r.errorLine.find("40000 triangles as seen") != std::string::npos);
    CHECK(r.errorLine.find("more than the --max-memory limit (4.0 MB)") != std::string::npos);
    CHECK_FALSE(std::ifstream(d.file("out.png")));
    r = run(base + " --max-memory 4Q");
    CHECK(r.rc == 1);
    CHECK(r.errorLine.find("--max-memory") != std::string::npos);
}

TEST_CASE("memory: a scene needing terabytes is refused before flattening, never killed; two-level it renders", "[memory][cli]") {
    // 10,000 placements of a 180,000-triangle field: 1.8 billion triangles as seen, ~860 GB flattened.
    TempDir d;
    writeHeightField(d.file("field.ply"), 300);
    writeFileBytes(d.file("s.xml"), instancedScene("field.ply", 10000));
    const std::string base = "render " + d.file("s.xml") + " -o " + d.path.string() + deviceArg();
    const int rc = runClrt(base + " --instancing flatten", d.file("log"));
    const CliResult r = cliResult(rc, readFileBytes(d.file("log")));
    INFO(r.log);
    CHECK(r.rc == 2);
    CHECK(r.errorLines == 1);
    CHECK(r.errorLine.find("1800000000 triangles as seen") != std::string::npos);
    CHECK(r.errorLine.find(" of host memory") != std::string::npos);
    CHECK(r.errorLine.find("more than what the machine has available") != std::string::npos);
    // The default (--instancing auto) keeps the mesh once under its own BVH: the estimate fits, it renders.
    const int rc2 = runClrt(base, d.file("log2"));
    const CliResult r2 = cliResult(rc2, readFileBytes(d.file("log2")));
    INFO(r2.log);
    CHECK(r2.rc == 0);
}
