// The clrt binary's outputs under hostile scenes and careless use (issue 12): output names that try to
// leave OUTDIR, outputs that would destroy an input or each other, an unwritable OUTDIR, no OpenCL
// device (or an unusable HOME), and Ctrl-C / SIGTERM during a render. Every case runs the binary and
// checks the exit code, exactly one "clrt: error:" line naming the file, that nothing was written
// outside OUTDIR, that no input changed, and that no temporary file was left behind. The signal cases
// start the binary in the background, wait (with a generous bound) for its "rendering" line, signal
// it, and render 256x256 pixels at --spp 1048576 (one sample of every pixel per batch, a million
// batches) so that the render can never finish before the signal: the outcome does not depend on the
// machine's speed.
#include <catch.hpp>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <thread>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>

#include "image/image.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;
namespace fs = std::filesystem;

extern char** environ;

namespace {


using Result = CliResult;


// `env... clrt args` through the shell; stdout and stderr together.
Result run(const TempDir& d, const std::string& args, const std::string& env = "") {
    const std::string log = d.file("clrt.log");
    const std::string cmd = env + " " + CLRT_BINARY + " " + args + " >'" + log + "' 2>&1";
    const int rc = std::system(cmd.c_str());
    return cliResult(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, readFileBytes(log));
}

void expectRefused(const Result& r, int rc, std::initializer_list<std::string> needles) {
    INFO("output:\n" << r.log);
    CHECK(r.rc == rc);
    CHECK(r.errorLines == 1);
    for (const std::string& n : needles) CHECK(r.errorLine.find(n) != std::string::npos);
    CHECK(r.log.find("rendering") == std::string::npos);  // refused before any work
}

// Every regular file and symlink under `root` (relative paths) with its content.
std::map<std::string, std::string> snapshot(const fs::path& root) {
    std::map<std::string, std::string> files;
    for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
        const std::string rel = fs::relative(it->path(), root).string();
        if (it->is_symlink()) files[rel] = "-> " + fs::read_symlink(it->path()).string();
        else if (it->is_regular_file()) files[rel] = readFileBytes(it->path().string());
    }
    return files;
}

// Nothing but the log changed under root.
void expectUnchanged(const std::map<std::string, std::string>& before, const fs::path& root) {
    auto after = snapshot(root);
    after.erase("clrt.log");
    auto b = before;
    b.erase("clrt.log");
    CHECK(after == b);
}

void expectNoTemporaries(const fs::path& root) {
    for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
        INFO(it->path());
        CHECK(it->path().filename().string().find(".tmp-") == std::string::npos);
    }
}

// A one-camera scene (or cameras given whole) with one triangle.
std::string sceneXml(const std::string& cameras, const std::string& extra = "") {
    return "<Scene>\n<Cameras>" + cameras +
           "</Cameras>\n<Lights><PointLight id=\"1\"><Position>0 0 5</Position><Intensity>100 100 100</Intensity>"
           "</PointLight></Lights>\n<Materials><Material id=\"1\"><DiffuseReflectance>1 1 1</DiffuseReflectance>"
           "</Material></Materials>\n<VertexData>-1 -1 0 1 -1 0 0 1 0</VertexData>\n"
           "<TexCoordData>0 0 1 0 0.5 1</TexCoordData>\n" +
           extra + "\n<Objects><Triangle id=\"1\"><Indices>1 2 3</Indices><Material>1</Material>" +
           (extra.empty() ? "" : "<Textures>1</Textures>") + "</Triangle></Objects>\n</Scene>\n";
}
std::string camera(int id, const std::string& imageName, const std::string& tonemaps = "", const std::string& res = "4 4") {
    return "<Camera id=\"" + std::to_string(id) +
           "\"><Position>0 0 5</Position><Gaze>0 0 -1</Gaze><Up>0 1 0</Up><NearPlane>-1 1 -1 1</NearPlane>"
           "<NearDistance>1</NearDistance><ImageResolution>" + res + "</ImageResolution><ImageName>" + imageName +
           "</ImageName>" + tonemaps + "</Camera>";
}
std::string tonemap(const std::string& extension) {
    return "<Tonemap><TMO>Photographic</TMO><TMOOptions>0.18 1</TMOOptions><Saturation>1</Saturation>"
           "<Gamma>2.2</Gamma>" + (extension.empty() ? "" : "<Extension>" + extension + "</Extension>") + "</Tonemap>";
}
std::string textureBlock(const std::string& image) {
    return "<Textures><Images><Image id=\"1\">" + image +
           "</Image></Images><TextureMap id=\"1\" type=\"image\"><ImageId>1</ImageId>"
           "<DecalMode>replace_kd</DecalMode></TextureMap></Textures>";
}

void makeExrFile(const std::string& path) {
    ImageRGB img;
    img.width = img.height = 8;
    img.pixels.assign(8 * 8 * 3, 0.5f);
    for (size_t i = 0; i < img.pixels.size(); ++i) img.pixels[i] = float(i % 17) * 0.1f;
    writeExr(path, img);
}

}  // namespace

TEST_CASE("cli output: names that would leave OUTDIR are refused (exit 2)", "[cli][output]") {
    TempDir d;
    fs::create_directories(d.path / "out" / "deep");
    const std::string f = d.file("s.xml");
    auto refused = [&](const std::string& cameras, std::initializer_list<std::string> needles) {
        writeFileBytes(f, sceneXml(cameras));
        const auto before = snapshot(d.path);
        expectRefused(run(d, "render " + f + " -o " + d.file("out/deep")), 2, needles);
        expectUnchanged(before, d.path);
    };
    SECTION("Tonemap Extension with .. and /, ImageName ..exr") {
        refused(camera(1, "..exr", tonemap("/../../escaped")), {"s.xml", "camera 1", "..exr"});
    }
    SECTION("Tonemap Extension climbing out of OUTDIR") {
        refused(camera(1, "a.exr", tonemap("/../../escaped")), {"s.xml", "camera 1", "Extension", "not a plain file name"});
    }
    SECTION("Extension of one of several blocks") {
        refused(camera(1, "a.exr", tonemap("_ok") + tonemap("/../x")), {"s.xml", "a/../x.png"});
    }
    SECTION("ImageName with a directory, absolute, or a backslash") {
        refused(camera(1, "sub/x.png"), {"s.xml", "sub/x.png", "directory separator"});
        refused(camera(1, d.file("abs.png")), {"s.xml", "directory separator"});
        refused(camera(1, "..\\x.png"), {"s.xml"});
    }
    SECTION("ImageName ., .., hidden, control character, too long") {
        refused(camera(1, "."), {"s.xml", "starts with '.'"});
        refused(camera(1, ".."), {"s.xml"});
        refused(camera(1, ".bashrc"), {"s.xml", ".bashrc"});
        refused(camera(1, ".png"), {"s.xml"});
        refused(camera(1, "a&#10;b.png"), {"s.xml", "control character", "\\x0a"});
        refused(camera(1, std::string(220, 'a') + ".png"), {"s.xml", "200 bytes"});
    }
    CHECK(!fs::exists(d.path / "out" / "escaped.png"));
    CHECK(!fs::exists(d.path / "escaped.png"));
}

TEST_CASE("cli output: wrong image types, inputs and duplicates are refused before any work (exit 2)",
          "[cli][output]") {
    TempDir d;
    const std::string f = d.file("s.xml");
    auto refused = [&](const std::string& file, const std::string& text, const std::string& outDir,
                       std::initializer_list<std::string> needles) {
        writeFileBytes(file, text);
        const auto before = snapshot(d.path);
        expectRefused(run(d, "render " + file + " -o " + outDir), 2, needles);
        expectUnchanged(before, d.path);
    };
    SECTION("extension not .png/.exr: the scene's own name, a JPEG, none") {
        refused(f, sceneXml(camera(1, "s.xml")), d.path.string(), {"s.xml", "must end in .png or .exr"});
        refused(f, sceneXml(camera(1, "out.jpg")), d.path.string(), {"s.xml", "out.jpg", "must end in .png or .exr"});
        refused(f, sceneXml(camera(1, "noext")), d.path.string(), {"s.xml", "noext"});
    }
    SECTION("the scene file itself (a scene named .png)") {
        const std::string g = d.file("scene.png");
        refused(g, sceneXml(camera(1, "scene.png")), d.path.string(), {"scene.png", "would overwrite the input file"});
    }
    SECTION("a texture, directly and through a symlink or hard link in OUTDIR") {
        ImageRGB img;
        img.width = img.height = 4;
        img.pixels.assign(48, 100.0f);
        writePngClamped(d.file("tex.png"), img);
        refused(f, sceneXml(camera(1, "tex.png"), textureBlock("tex.png")), d.path.string(),
                {"s.xml", "tex.png", "would overwrite the input file"});
        fs::create_directories(d.path / "out");
        fs::create_symlink(d.path / "tex.png", d.path / "out" / "link.png");
        refused(f, sceneXml(camera(1, "link.png"), textureBlock("tex.png")), d.file("out"),
                {"s.xml", "link.png", "would overwrite the input file"});
        fs::create_hard_link(d.path / "tex.png", d.path / "out" / "hard.png");
        refused(f, sceneXml(camera(1, "hard.png"), textureBlock("tex.png")), d.file("out"), {"s.xml", "hard.png"});
    }
    SECTION("a PLY file named like an output") {
        writeFileBytes(d.file("mesh.png"), "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                    "end_header\n-1 -1 0\n1 -1 0\n0 1 0\n3 0 1 2\n");
        std::string text = sceneXml(camera(1, "mesh.png"));
        text.replace(text.find("<Objects>"), 9,
                     "<Objects><Mesh id=\"2\"><Material>1</Material><Faces plyFile=\"mesh.png\"/></Mesh>");
        refused(f, text, d.path.string(), {"s.xml", "mesh.png", "would overwrite the input file"});
    }
    SECTION("two cameras with one ImageName; a derived PNG equal to another camera's; names differing in case") {
        refused(f, sceneXml(camera(1, "a.png") + camera(2, "a.png")), d.path.string(),
                {"s.xml", "camera 2", "camera 1", "same output file"});
        refused(f, sceneXml(camera(1, "a.exr", tonemap("")) + camera(2, "a.png")), d.path.string(),
                {"s.xml", "camera 2", "a.png", "camera 1"});
        refused(f, sceneXml(camera(1, "b.exr", tonemap("_x")) + camera(2, "b_x.png")), d.path.string(),
                {"s.xml", "b_x.png"});
        refused(f, sceneXml(camera(1, "A.png") + camera(2, "a.png")), d.path.string(), {"s.xml", "same output file"});
    }
}

TEST_CASE("cli output: accepted names, upper-case extensions, and a final symlink that is replaced, not followed",
          "[cli][output]") {
    TempDir d;
    fs::create_directories(d.path / "out");
    fs::create_directories(d.path / "elsewhere");
    writeFileBytes(d.file("elsewhere/victim.png"), "not to be touched");
    fs::create_symlink(d.path / "elsewhere" / "victim.png", d.path / "out" / "shot.png");
    const std::string f = d.file("s.xml");
    writeFileBytes(f, sceneXml(camera(1, "shot.png") + camera(2, "UPPER.EXR", tonemap(""))));
    Result r = run(d, "render " + f + " -o " + d.file("out") + deviceArg());
    INFO(r.log);
    REQUIRE(r.rc == 0);
    CHECK(readFileBytes(d.file("elsewhere/victim.png")) == "not to be touched");
    CHECK(!fs::is_symlink(d.path / "out" / "shot.png"));
    CHECK(readImage(d.file("out/shot.png")).width == 4);
    CHECK(readImage(d.file("out/UPPER.EXR")).width == 4);
    CHECK(fs::exists(d.path / "out" / "UPPER.png"));
    expectNoTemporaries(d.path);
}

TEST_CASE("cli output: clrt tonemap never overwrites its input and checks its output name", "[cli][output]") {
    TempDir d;
    makeExrFile(d.file("a.exr"));
    ImageRGB img;
    img.width = img.height = 4;
    img.pixels.assign(48, 100.0f);
    writePngClamped(d.file("x.png"), img);
    const auto before = snapshot(d.path);
    auto refused = [&](const std::string& args, int rc, std::initializer_list<std::string> needles) {
        Result r = run(d, "tonemap " + args + deviceArg());
        INFO(r.log);
        CHECK(r.rc == rc);
        CHECK(r.errorLines == 1);
        for (const std::string& n : needles) CHECK(r.errorLine.find(n) != std::string::npos);
        CHECK(r.log.find("wrote") == std::string::npos);
        expectUnchanged(before, d.path);
    };
    refused(d.file("x.png"), 2, {"x.png", "would overwrite the input file"});  // default output: x.png
    refused(d.file("a.exr") + " -o " + d.file("a.exr"), 2, {"a.exr", "would overwrite the input file"});
    fs::create_directories(d.path / "o");
    refused(d.file("a.exr") + " -o " + d.file("o/b.txt"), 2, {"b.txt", "must end in .png or .exr"});
    refused(d.file("a.exr") + " -o " + d.file("o/.hidden.png"), 2, {".hidden.png", "not a plain file name"});
    refused(d.file("a.exr") + " -o " + d.file("o/"), 2, {"not a plain file name"});
    refused(d.file("a.exr") + " -o " + d.file("nodir/b.png"), 4, {"nodir", "does not exist"});
    // And a good one writes exactly its output.
    Result ok = run(d, "tonemap " + d.file("a.exr") + " -o " + d.file("o/b.png") + deviceArg());
    INFO(ok.log);
    CHECK(ok.rc == 0);
    CHECK(readImage(d.file("o/b.png")).width == 8);
    expectNoTemporaries(d.path);
}

TEST_CASE("cli output: an output directory that cannot be written is reported before any work (exit 4)",
          "[cli][output]") {
    TempDir d;
    const std::string f = d.file("s.xml");
    writeFileBytes(f, sceneXml(camera(1, "out.exr", tonemap(""))));
    fs::create_directories(d.path / "out" / "out.png");  // the tone-mapped PNG's name is taken by a directory
    expectRefused(run(d, "render " + f + " -o " + d.file("out") + deviceArg()), 4, {"out.png", "a directory has its name"});
    CHECK(!fs::exists(d.path / "out" / "out.exr"));
    // As root, permissions do not stop a write: /proc/self is a directory no one can create files in.
    if (!fs::is_directory("/proc/self")) {
        WARN("no /proc: skipped");
        return;
    }
    Result r = run(d, "render " + f + " -o /proc/self --spp 1048576" + deviceArg());
    expectRefused(r, 4, {"/proc/self", "output directory is not writable"});
    CHECK(r.log.find("stats:") == std::string::npos);
    Result t = run(d, "tonemap " + f + " -o /proc/self/x.png" + deviceArg());  // before the input is read
    INFO(t.log);
    CHECK(t.rc == 4);
    CHECK(t.errorLines == 1);
    CHECK(t.errorLine.find("not writable") != std::string::npos);
}

TEST_CASE("cli output: no OpenCL device, and an unusable HOME, are one error line with the cause (exit 3)",
          "[cli][output]") {
    TempDir d;
    fs::create_directories(d.path / "vendors");
    const std::string noIcd = "OCL_ICD_VENDORS='" + d.file("vendors") + "'";
    SECTION("clrt devices with no device") {
        Result r = run(d, "devices", noIcd);
        INFO(r.log);
        CHECK(r.rc == 3);
        CHECK(r.errorLines == 1);
        CHECK(r.errorLine.find("no OpenCL devices found") != std::string::npos);
        CHECK(r.log == r.errorLine + "\n");  // nothing on stdout
    }
    SECTION("HOME that PoCL cannot make its cache in") {
        std::string pocl;
        if (fs::is_directory("/etc/OpenCL/vendors"))
            for (auto& e : fs::directory_iterator("/etc/OpenCL/vendors"))
                if (readFileBytes(e.path().string()).find("pocl") != std::string::npos) pocl = e.path().string();
        if (pocl.empty()) {
            WARN("no PoCL ICD registered: skipped");
            return;
        }
        fs::copy_file(pocl, d.path / "vendors" / "pocl.icd");  // PoCL alone, whatever else is installed
        // HOME is a regular file: no one (root included, /proc mounted or not) can create a directory in it.
        const std::string home = d.file("home-is-a-file");
        writeFileBytes(home, "x");
        const std::string env = "env -u POCL_CACHE_DIR -u XDG_CACHE_HOME HOME='" + home + "' " + noIcd;
        Result r = run(d, "devices", env);
        INFO(r.log);
        CHECK(r.rc == 3);
        CHECK(r.errorLines == 1);
        CHECK(r.errorLine.find("kernel cache directory " + home + "/.cache/pocl/kcache") != std::string::npos);
        CHECK(r.errorLine.find("HOME=" + home) != std::string::npos);
        const std::string f = d.file("s.xml");
        writeFileBytes(f, sceneXml(camera(1, "out.png")));
        fs::create_directories(d.path / "out");
        Result rr = run(d, "render " + f + " -o " + d.file("out"), env);
        INFO(rr.log);
        CHECK(rr.rc == 3);
        CHECK(rr.errorLines == 1);
        CHECK(rr.errorLine.find("HOME=" + home) != std::string::npos);
        CHECK(fs::is_empty(d.path / "out"));
        // With a writable cache directory the same setup finds the device.
        Result ok = run(d, "devices", "env -u POCL_CACHE_DIR XDG_CACHE_HOME='" + d.file("cache") + "' HOME='" + home +
                                          "' " + noIcd);
        INFO(ok.log);
        CHECK(ok.rc == 0);
    }
}

// ---- signals ---------------------------------------------------------------------------------------

namespace {

struct Background {
    pid_t pid = -1;
    std::string log;
};

// Starts `clrt args...` with its output in `log` and `extraEnv` added to the environment.
Background spawn(const std::vector<std::string>& args, const std::string& log, const std::vector<std::string>& extraEnv = {}) {
    std::vector<std::string> argStore = {CLRT_BINARY};
    argStore.insert(argStore.end(), args.begin(), args.end());
    std::vector<std::string> envStore = extraEnv;
    for (char** e = environ; *e; ++e) envStore.push_back(*e);
    std::vector<char*> argv, envp;
    for (auto& a : argStore) argv.push_back(a.data());
    for (auto& e : envStore) envp.push_back(e.data());
    argv.push_back(nullptr);
    envp.push_back(nullptr);
    Background b;
    b.log = log;
    b.pid = fork();
    if (b.pid == 0) {  // only async-signal-safe calls until exec
        const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd < 0) _exit(127);
        ::dup2(fd, 1);
        ::dup2(fd, 2);
        ::execve(argv[0], argv.data(), envp.data());
        _exit(127);
    }
    return b;
}

// Waits (bounded, generously: the outcome never depends on it) until the log holds `text`.
bool waitForLog(const Background& b, const std::string& text, int seconds = 300) {
    for (int i = 0; i < seconds * 50; ++i) {
        if (readFileBytes(b.log).find(text) != std::string::npos) return true;
        int status = 0;
        if (waitpid(b.pid, &status, WNOHANG) == b.pid) return readFileBytes(b.log).find(text) != std::string::npos;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return false;
}

// The exit status (128 + signal if killed), waiting at most `seconds`; kills it past that.
int waitExit(const Background& b, int seconds = 300) {
    for (int i = 0; i < seconds * 50; ++i) {
        int status = 0;
        if (waitpid(b.pid, &status, WNOHANG) == b.pid)
            return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status) + 1000;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    kill(b.pid, SIGKILL);
    waitpid(b.pid, nullptr, 0);
    return -1;
}

std::string exrAttribute(const std::string& path, const std::string& name) {
    Imf::InputFile f(path.c_str());
    const auto* a = f.header().findTypedAttribute<Imf::StringAttribute>(name);
    return a ? a->value() : std::string("<none>");
}

std::vector<std::string> renderArgs(const TempDir& d) {
    std::vector<std::string> args = {"render", d.file("s.xml"), "-o", d.file("out"), "--spp", "1048576"};
    const char* dev = std::getenv("CLRT_TEST_DEVICE");
    args.push_back("--device");
    args.push_back(dev && *dev ? dev : "cpu");
    return args;
}

}  // namespace

TEST_CASE("cli output: the first SIGINT/SIGTERM/SIGHUP writes the partial image, the second exits at once", "[cli][output][signal]") {
    TempDir d;
    fs::create_directories(d.path / "out");
    // Two cameras: the second is not rendered after the interrupt.
    writeFileBytes(d.file("s.xml"), sceneXml(camera(1, "shot.exr", tonemap(""), "256 256") + camera(2, "second.png")));
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
        DYNAMIC_SECTION("one signal: " << (sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : "SIGHUP")) {
            Background b = spawn(renderArgs(d), d.file("clrt.log"));
            REQUIRE(waitForLog(b, "shot.exr, 256x256, 1048576 spp): rendering"));
            kill(b.pid, sig);
            const int rc = waitExit(b);
            const std::string log = readFileBytes(b.log);
            INFO(log);
            CHECK(rc == 128 + sig);
            CHECK(log.find("clrt: error") == std::string::npos);
            REQUIRE(fs::exists(d.path / "out" / "shot.exr"));
            const int spp = std::stoi(exrAttribute(d.file("out/shot.exr"), "spp"));
            CHECK(spp >= 1);
            CHECK(spp < 1048576);
            CHECK(exrAttribute(d.file("out/shot.exr"), "partial").find("interrupted after " + std::to_string(spp)) == 0);
            CHECK(log.find(" spp=" + std::to_string(spp) + "\n") != std::string::npos);  // the stats line too
            CHECK(readImage(d.file("out/shot.png")).width == 256);  // the tone-mapped PNG is made too
            CHECK(!fs::exists(d.path / "out" / "second.png"));
            CHECK(log.find("partial images written") != std::string::npos);
            CHECK(log.find("cameras not rendered: 2") != std::string::npos);
            expectNoTemporaries(d.path);
        }
    }
    SECTION("a second signal while the temporaries exist: exit at once, none left, nothing committed") {
        // CLRT_TEST_STALL_OUTPUT holds the process after the partial image's temporaries are complete
        // and before they are renamed, so the second signal always finds them there.
        Background b = spawn(renderArgs(d), d.file("clrt.log"), {"CLRT_TEST_STALL_OUTPUT=1"});
        REQUIRE(waitForLog(b, "1048576 spp): rendering"));
        kill(b.pid, SIGINT);
        REQUIRE(waitForLog(b, "stalled before the rename"));
        size_t temporaries = 0;
        for (auto& e : fs::directory_iterator(d.path / "out"))
            temporaries += e.path().filename().string().find(".tmp-") != std::string::npos;
        CHECK(temporaries == 2);  // the EXR and its PNG
        kill(b.pid, SIGINT);
        const int rc = waitExit(b);
        INFO(readFileBytes(b.log));
        CHECK(rc == 130);
        CHECK(fs::is_empty(d.path / "out"));
        expectNoTemporaries(d.path);
    }
}
