// One image over several processes (src/dist/), through the clrt binary: job-array parts
// (`--part K/N` + `clrt merge`), checkpoints (`--checkpoint DIR`), and MPI ranks
// (`mpirun --oversubscribe --allow-run-as-root -np 3 clrt render`, tagged [mpi]; skipped with a
// warning when clrt was built without MPI or mpirun is missing). Every result is compared with a
// one-process render of the same scene on the same device: PNG bytes, EXR floats (EXR files differ
// only in their renderTime/device attributes). Renders are small (128x96, 4 spp, tiles of 1024
// pixels: 12 tiles) to keep the suite fast; the identity of the pixels does not depend on the size.
#include <catch.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <unistd.h>

#include "dist/tiles.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;
namespace fs = std::filesystem;

namespace {

const char* kTonemaps =
    "<Tonemap><TMO>Photographic</TMO><TMOOptions>0.18 1</TMOOptions><Saturation>1</Saturation><Gamma>2.2</Gamma></Tonemap>"
    "<Tonemap><TMO>ACES</TMO><TMOOptions>0.5 0</TMOOptions><Gamma>sRGB</Gamma><Extension>_aces</Extension></Tonemap>";

// The demo scene as an LDR (ldr.png) or HDR (hdr.exr + two tone-mapped PNGs) render.
std::string writeScene(const TempDir& dir, bool hdr) {
    std::string xml = readFileBytes(std::string(CLRT_SOURCE_DIR) + "/scenes/demo.xml");
    xml = std::regex_replace(xml, std::regex("<ImageName>demo\\.png</ImageName>"),
                             hdr ? std::string("<ImageName>hdr.exr</ImageName>") + kTonemaps : "<ImageName>ldr.png</ImageName>");
    const std::string path = dir.file(hdr ? "hdr.xml" : "ldr.xml");
    writeFileBytes(path, xml);
    return path;
}

std::string deviceSpec() {
    const char* d = std::getenv("CLRT_TEST_DEVICE");
    return d && *d ? d : "cpu";
}

// Runs `prefix clrt args` in `dir`; the log is stdout and stderr together.
CliResult run(const TempDir& dir, const std::string& prefix, const std::string& args) {
    const std::string log = dir.file("log.txt");
    const std::string cmd = "cd " + dir.path.string() + " && " + prefix + " " + CLRT_BINARY + " " + args + " >" + log + " 2>&1";
    const int rc = std::system(cmd.c_str());
    return cliResult(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readFileBytes(log));
}

const std::string kSmall = " --resolution 128x96 --tile-pixels 1024 --device ";

// mpirun with 3 ranks on this machine ("" when clrt has no MPI or mpirun is missing: the caller skips
// the test). A build that wanted MPI (CLRT_MPI=ON) but found none while mpirun is installed fails
// instead of skipping (a stale CMake cache from before the install; reconfigure). plm=isolated:
// local launch without ssh; no single-copy: containers without ptrace; hwloc without its OpenCL
// plugin: mpirun itself need not load PoCL.
std::string mpirun3() {
    const std::string exe = CLRT_MPIEXEC;
    if (exe.empty()) {
        if (std::string(CLRT_MPI_OPTION) == "1" && std::system("command -v mpirun >/dev/null 2>&1") == 0)
            FAIL("mpirun is installed but clrt was built without MPI: reconfigure (rm build/CMakeCache.txt)");
        return "";
    }
    if (access(exe.c_str(), X_OK) != 0) return "";
    return "env OMPI_MCA_plm=isolated OMPI_MCA_btl_vader_single_copy_mechanism=none HWLOC_COMPONENTS=-opencl " + exe +
           " --oversubscribe --allow-run-as-root -np 3";
}

// Every output of `a` is in `b` with the same PNG bytes / EXR floats and spp attribute.
void checkSameOutputs(const std::string& a, const std::string& b) {
    int n = 0;
    for (const auto& e : fs::directory_iterator(a)) {
        const std::string name = e.path().filename().string();
        INFO(name);
        REQUIRE(fs::exists(b + "/" + name));
        if (e.path().extension() == ".exr") {
            CHECK(readImage(a + "/" + name).pixels == readImage(b + "/" + name).pixels);
        } else {
            CHECK(readFileBytes(a + "/" + name) == readFileBytes(b + "/" + name));
        }
        ++n;
    }
    CHECK(n > 0);
}

size_t filesIn(const std::string& dir) {
    size_t n = 0;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(dir, ec); it != fs::recursive_directory_iterator(); ++it)
        n += it->is_regular_file();
    return n;
}

// The tile files of a checkpoint folder (a writer killed mid-write may leave a temporary beside them).
size_t checkpointTiles(const std::string& dir) {
    size_t n = 0;
    std::error_code ec;
    for (auto it = fs::recursive_directory_iterator(dir, ec); it != fs::recursive_directory_iterator(); ++it)
        n += std::regex_match(it->path().filename().string(), std::regex("tile-\\d+\\.bin"));
    return n;
}

// "checkpoint ...: N of M tiles were there already" -> N (-1 if absent).
int tilesFromCheckpoint(const std::string& log) {
    std::smatch m;
    return std::regex_search(log, m, std::regex("checkpoint .*: (\\d+) of 12 tiles were there already")) ? std::stoi(m[1]) : -1;
}

}  // namespace

TEST_CASE("tile lists and part tile sets", "[dist]") {
    for (int n : {1, 2, 3, 7}) {
        std::vector<int> owner(20, 0);
        for (int k = 1; k <= n; ++k)
            for (size_t t : partTiles(20, k, n)) ++owner[t];
        for (int o : owner) CHECK(o == 1);  // every tile in exactly one part
    }
    CHECK(formatTileList({0, 1, 2, 3, 7, 9, 10}) == "0-3,7,9-10");
    CHECK(parseTileList("0-3,7,9-10", 11, "x") == std::vector<size_t>{0, 1, 2, 3, 7, 9, 10});
    CHECK(parseTileList("", 4, "x").empty());
    CHECK_THROWS_WITH(parseTileList("1,1", 4, "p.exr"), Catch::Contains("p.exr") && Catch::Contains("listed twice"));
    CHECK_THROWS_WITH(parseTileList("2-9", 4, "p.exr"), Catch::Contains("beyond"));
    CHECK_THROWS_WITH(parseTileList("3-1", 4, "p.exr"), Catch::Contains("not a range"));
    CHECK_THROWS_WITH(parseTileList("a", 4, "p.exr"), Catch::Contains("not a number"));
    CHECK(defaultTilePixels(320 * 240) == 4096);
    CHECK(defaultTilePixels(1920 * 1080) == 32400);
    CHECK(defaultTilePixels(8000 * 8000) == 65536);
}

TEST_CASE("--part 1/3..3/3 and clrt merge give the one-process render's outputs; bad sets of parts are errors",
          "[dist][cli]") {
    TempDir dir;
    const bool hdr = GENERATE(false, true);
    INFO((hdr ? "EXR + tone-mapped scene" : "LDR scene"));
    const std::string scene = writeScene(dir, hdr), dev = kSmall + deviceSpec();
    for (const char* d : {"one", "parts", "merged", "bad", "spp2"}) fs::create_directories(dir.file(d));
    REQUIRE(run(dir, "", "render " + scene + " -o one" + dev).rc == 0);
    for (int k = 1; k <= 3; ++k) {
        CliResult r = run(dir, "", "render " + scene + " -o parts --part " + std::to_string(k) + "/3" + dev);
        INFO(r.log);
        REQUIRE(r.rc == 0);
    }
    CHECK(filesIn(dir.file("parts")) == 3);
    const std::string name = hdr ? "hdr.exr" : "ldr.png";
    const std::string p1 = "parts/" + name + ".part1of3.exr", p2 = "parts/" + name + ".part2of3.exr",
                      p3 = "parts/" + name + ".part3of3.exr";
    CliResult m = run(dir, "", "merge " + p1 + " " + p2 + " " + p3 + " -o merged --device " + deviceSpec());
    INFO(m.log);
    REQUIRE(m.rc == 0);
    checkSameOutputs(dir.file("one"), dir.file("merged"));
    CHECK(filesIn(dir.file("merged")) == filesIn(dir.file("one")));

    // Each error: exit 2, one line naming the offending file, nothing written.
    auto refused = [&](const std::string& args, const std::string& file, const std::string& what) {
        CliResult r = run(dir, "", "merge " + args + " -o bad --device " + deviceSpec());
        INFO(r.log);
        CHECK(r.rc == 2);
        CHECK(r.errorLines == 1);
        CHECK(r.errorLine.find(file) != std::string::npos);
        CHECK(r.errorLine.find(what) != std::string::npos);
        CHECK(filesIn(dir.file("bad")) == 0);
    };
    refused(p1 + " " + p2, p1, "part 3/3 not given");  // missing
    fs::copy_file(dir.file(p2), dir.file("copy.exr"));
    refused(p1 + " " + p2 + " " + p3 + " copy.exr", "copy.exr", "overlaps " + p2);  // overlapping
    REQUIRE(run(dir, "", "render " + scene + " -o spp2 --spp 2 --part 3/3" + dev).rc == 0);
    refused(p1 + " " + p2 + " spp2/" + name + ".part3of3.exr", "spp2/", "spp 2");  // another spp
    refused(p1 + " " + p2 + " one/" + name, "one/" + name, hdr ? "not a clrt part file" : "not a readable OpenEXR");
}

TEST_CASE("--checkpoint: a render that failed goes on where it stopped and gives the same image", "[dist][cli]") {
    TempDir dir;
    const std::string scene = writeScene(dir, true), dev = kSmall + deviceSpec();
    fs::create_directories(dir.file("one"));
    fs::create_directories(dir.file("out"));
    REQUIRE(run(dir, "", "render " + scene + " -o one" + dev).rc == 0);
    writeFileBytes(dir.file("out/hdr.exr"), "a good image");
    // Every device fails at its 4th tile (CLRT_FAIL_DEVICE): 3 tiles are in the checkpoint.
    CliResult failed = run(dir, "CLRT_FAIL_DEVICE=-1:3", "render " + scene + " -o out --checkpoint ck" + dev);
    INFO(failed.log);
    CHECK(failed.rc == 3);
    CHECK(readFileBytes(dir.file("out/hdr.exr")) == "a good image");
    CHECK(checkpointTiles(dir.file("ck")) == 3);
    CliResult again = run(dir, "", "render " + scene + " -o out --checkpoint ck" + dev);
    INFO(again.log);
    REQUIRE(again.rc == 0);
    CHECK(tilesFromCheckpoint(again.log) == 3);
    checkSameOutputs(dir.file("one"), dir.file("out"));
    CHECK(checkpointTiles(dir.file("ck")) == 12);
    // Another spp is another checkpoint: nothing reused.
    CliResult other = run(dir, "", "render " + scene + " -o out --spp 1 --checkpoint ck" + dev);
    CHECK(tilesFromCheckpoint(other.log) == 0);
}

TEST_CASE("mpirun -np 3: the same image as one process, LDR and EXR + tone mapping", "[mpi]") {
    const std::string mpi = mpirun3();
    if (mpi.empty()) {
        WARN("clrt built without MPI, or mpirun not found: [mpi] tests skipped");
        return;
    }
    TempDir dir;
    const bool hdr = GENERATE(false, true);
    INFO((hdr ? "EXR + tone-mapped scene" : "LDR scene"));
    const std::string scene = writeScene(dir, hdr), dev = kSmall + deviceSpec();
    fs::create_directories(dir.file("one"));
    fs::create_directories(dir.file("mpi"));
    REQUIRE(run(dir, "", "render " + scene + " -o one" + dev).rc == 0);
    CliResult r = run(dir, mpi, "render " + scene + " -o mpi" + dev);
    INFO(r.log);
    REQUIRE(r.rc == 0);
    checkSameOutputs(dir.file("one"), dir.file("mpi"));
    CHECK(filesIn(dir.file("mpi")) == filesIn(dir.file("one")));
    // One progress line for the image (rank 0's), one summary line per rank, one stats line.
    CHECK(std::regex_search(r.log, std::regex("camera 1 \\(.*\\) done")));
    CHECK(std::count(r.log.begin(), r.log.end(), '\n') < 40);
    for (const char* rank : {"rank 0 (", "rank 1: ", "rank 2: "}) CHECK(r.log.find(rank) != std::string::npos);
    CHECK(std::regex_search(r.log, std::regex("(^|\n)stats: ")));
}

TEST_CASE("mpirun -np 3: a rank killed mid-render fails the job cleanly; --checkpoint finishes it identically", "[mpi]") {
    const std::string mpi = mpirun3();
    if (mpi.empty()) {
        WARN("clrt built without MPI, or mpirun not found: [mpi] tests skipped");
        return;
    }
    TempDir dir;
    const std::string scene = writeScene(dir, true), dev = kSmall + deviceSpec();
    for (const char* d : {"one", "out", "out2"}) fs::create_directories(dir.file(d));
    REQUIRE(run(dir, "", "render " + scene + " -o one" + dev).rc == 0);
    for (const char* f : {"out/hdr.exr", "out/hdr_photographic.png", "out/hdr_aces.png"}) writeFileBytes(dir.file(f), "good");
    // Rank 1 dies (SIGKILL) when handed its third tile; its first two are in the checkpoint by then.
    // After such a failure Debian 12's mpirun (OpenMPI 4.1.4 with PMIx) now and then hangs or crashes in
    // its own PMIx_server_finalize, after every rank is gone and its messages are printed (about 1 run
    // in 20 here): `timeout` ends such an mpirun. It changes no outcome: the job has failed by then.
    CliResult killed = run(dir, "CLRT_KILL_RANK=1:2 timeout -k 5 60 " + mpi, "render " + scene + " -o out --checkpoint ck" + dev);
    INFO(killed.log);
    CHECK(killed.rc != 0);
    CHECK(std::regex_search(killed.log, std::regex("rank 1 .*(signal 9|Killed)")));  // mpirun names the rank
    for (const char* f : {"out/hdr.exr", "out/hdr_photographic.png", "out/hdr_aces.png"})
        CHECK(readFileBytes(dir.file(f)) == "good");
    CHECK(filesIn(dir.file("out")) == 3);  // no temporary left
    const size_t kept = checkpointTiles(dir.file("ck"));
    CHECK(kept >= 2);
    CHECK(kept < 12);
    fs::copy(dir.file("ck"), dir.file("ck2"), fs::copy_options::recursive);

    CliResult again = run(dir, mpi, "render " + scene + " -o out --checkpoint ck" + dev);
    INFO(again.log);
    REQUIRE(again.rc == 0);
    CHECK(tilesFromCheckpoint(again.log) == int(kept));
    checkSameOutputs(dir.file("one"), dir.file("out"));
    // The same checkpoint finished by one process instead.
    CliResult single = run(dir, "", "render " + scene + " -o out2 --checkpoint ck2" + dev);
    REQUIRE(single.rc == 0);
    CHECK(tilesFromCheckpoint(single.log) == int(kept));
    checkSameOutputs(dir.file("one"), dir.file("out2"));
}
