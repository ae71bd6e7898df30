// tonemap_cmd.cpp — `clrt tonemap` (see tonemap_cmd.h): options, the Tonemap blocks of a scene
// camera, the output checks, then tone mapping on the device and atomic writes.
#include "cli/tonemap_cmd.h"

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "cl/devices.h"
#include "cli/args.h"
#include "cli/output_names.h"
#include "image/image.h"
#include "output/output.h"
#include "output/tonemap_device.h"
#include "scene/scene_loader.h"
#include "util/error.h"

namespace clrt {
namespace fs = std::filesystem;

const char* const kTonemapHelp =
    "usage: clrt tonemap IN.exr [-o OUT.png] [options]\n"
    "\n"
    "Tone-maps an HDR image (EXR; PNG/JPG are read as 0..255 values) on the OpenCL device and writes an\n"
    "8-bit PNG, without re-rendering. Settings come from the options, else from a scene camera's\n"
    "Tonemap blocks (--scene/--camera; several blocks give several PNGs, named as `clrt render`\n"
    "names them), else the defaults below. Explicit options override the scene's.\n"
    "\n"
    "options:\n"
    "  -o, --output OUT.png  output PNG (default: IN with the extension .png); OUT.exr instead writes\n"
    "                        the display values (gamma applied, in [0,1]) as float, not quantised.\n"
    "                        Must end in .png or .exr and never names the input or a --scene file\n"
    "  --tmo NAME            photographic (Reinhard 2002, global; default), aces (Narkowicz's fit)\n"
    "                        or filmic (Hable's Uncharted 2 curve, white point 11.2)\n"
    "  --key K               key value a: L = a·Y / log-average(Y) (default 0.18)\n"
    "  --burn P              photographic: percentage of pixels burnt out to white (default 1;\n"
    "                        0: no white point)\n"
    "  --saturation S        RGBo = Yo·(RGB/Y)^S (default 1)\n"
    "  --gamma G             8-bit value of c is 255·c^(1/G) (default 2.2); sRGB: the sRGB curve\n"
    "  --quantize MODE       floor (default; the course's reference PNGs) or round\n"
    "  --delta D             the δ of the log-average exp(mean(log(δ + Y))) (default 1e-6)\n"
    "  --scene S.xml         take the Tonemap settings of a camera of this scene\n"
    "  --camera ID           that camera (default: the scene's only camera)\n"
    "  --device SPEC         OpenCL device, as for `clrt render` (default: first GPU, else CPU)\n"
    "  -v, --verbose         print the log-average luminance and L_white\n"
    "  -h, --help            this text\n"
    "\n"
    "conventions: Y = 0.2126R + 0.7152G + 0.0722B (NaN/Inf/negative channels count as 0); log-average\n"
    "exp(mean(log(1e-6 + Y))); L_white = the sorted-array (100 - burn)th percentile of L, nearest rank.\n";

namespace {

std::string lowerAscii(std::string v) {
    for (char& c : v) c = char(std::tolower(static_cast<unsigned char>(c)));
    return v;
}

struct TonemapArgs {
    std::string in, outPath, scenePath, cameraId, deviceSpec;
    bool haveTmo = false, haveKey = false, haveBurn = false, haveSat = false, haveGamma = false, haveDelta = false;
    TonemapSettings over;  // the explicit options (each with its have* flag)
    bool truncate = true;
    bool help = false;
};

// A float option that sets `target` and `have`.
ArgOption floatOption(const char* name, float& target, bool& have) {
    return {{name}, true, [&target, &have](const std::string& f, const std::string& v) {
                target = parseFloatArg(f, v);
                have = true;
            }};
}

TonemapArgs parseTonemapArgs(int argc, char** argv) {
    TonemapArgs a;
    TonemapSettings& o = a.over;
    bool verboseFlag = false;
    using Str = const std::string&;
    const std::vector<std::string> positional = parseArgs(argc, argv, 2, {
        flagOption({"-h", "--help"}, a.help),
        textOption({"-o", "--output"}, a.outPath),
        {{"--tmo"}, true, [&](Str, Str v) { o.op = parseTmoKind(v); a.haveTmo = true; }},
        floatOption("--key", o.key, a.haveKey),
        floatOption("--burn", o.burnPercent, a.haveBurn),
        floatOption("--saturation", o.saturation, a.haveSat),
        {{"--gamma"}, true, [&](Str f, Str v) {
             o.srgb = lowerAscii(v) == "srgb";
             if (!o.srgb) o.gamma = parseFloatArg(f, v);
             a.haveGamma = true;
         }},
        {{"--quantize"}, true, [&](Str f, Str v) { a.truncate = parseChoiceArg(f, v, {"round", "floor"}) == 1; }},
        {{"--delta"}, true, [&](Str f, Str v) { o.delta = parseFloatArg(f, v); a.haveDelta = true; }},
        textOption({"--scene"}, a.scenePath),
        textOption({"--camera"}, a.cameraId),
        textOption({"--device"}, a.deviceSpec),
        flagOption({"-v", "--verbose"}, verboseFlag),
    }, "tonemap");
    if (verboseFlag) setVerbose(true);
    if (a.help) return a;
    if (positional.size() != 1) throw Error("tonemap: expected exactly one input image (see clrt tonemap --help)", ExitCode::Usage);
    if (!a.cameraId.empty() && a.scenePath.empty()) throw Error("tonemap: --camera needs --scene", ExitCode::Usage);
    a.in = positional[0];
    if (a.outPath.empty()) a.outPath = (fs::path(a.in).parent_path() / fs::path(a.in).stem()).string() + ".png";
    return a;
}

// The Tonemap blocks of the --scene camera, or one default block.
std::vector<TonemapSettings> sceneBlocks(const TonemapArgs& a, const Scene* scene) {
    if (!scene) return std::vector<TonemapSettings>(1);
    const Camera* cam = nullptr;
    for (const Camera& c : scene->cameras)
        if (a.cameraId.empty() ? scene->cameras.size() == 1 : std::to_string(c.id) == a.cameraId) cam = &c;
    if (!cam)
        throw Error(a.scenePath + (a.cameraId.empty() ? ": the scene has " + std::to_string(scene->cameras.size()) +
                                                             " cameras; choose one with --camera"
                                                       : ": no camera with id " + a.cameraId));
    if (cam->tonemaps.empty()) throw Error(a.scenePath + ": camera " + std::to_string(cam->id) + " has no Tonemap block");
    return cam->tonemaps;
}

// The explicit options applied to every block (the operator too, so the output names follow it).
void applyOptions(const TonemapArgs& a, std::vector<TonemapSettings>& blocks) {
    for (TonemapSettings& s : blocks) {
        if (a.haveTmo) s.op = a.over.op;
        if (a.haveKey) s.key = a.over.key;
        if (a.haveBurn) s.burnPercent = a.over.burnPercent;
        if (a.haveSat) s.saturation = a.over.saturation;
        if (a.haveGamma) { s.gamma = a.over.gamma; s.srgb = a.over.srgb; }
        if (a.haveDelta) s.delta = a.over.delta;
        s.truncate = a.truncate;
        validateTonemapSettings(s, "tonemap");
    }
}

// The output paths (with several blocks, -o gives the stem the block names are added to), each a
// plain .png/.exr name in the -o directory, no two alike.
std::vector<PlannedOutput> planTonemapOutputs(const std::string& outPath, const std::vector<TonemapSettings>& blocks) {
    const fs::path dir = fs::path(outPath).parent_path();
    const std::string name = fs::path(outPath).filename().string(), ext = lowerExtension(name);
    auto refuse = [&](const std::string& n, const std::string& why) {
        throw Error(outPath + ": output name '" + n + "' " + why);
    };
    if (!plainNameProblem(name).empty()) refuse(name, "is not a plain file name (" + plainNameProblem(name) + ")");
    if (ext != ".png" && ext != ".exr") refuse(name, "must end in .png or .exr");
    std::vector<std::string> names = {name};
    if (blocks.size() > 1) {
        names = tonemapPngPaths(name, blocks);
        if (ext == ".exr")
            for (std::string& n : names) n = fs::path(n).replace_extension(".exr").string();
    }
    std::vector<PlannedOutput> out;
    for (const std::string& n : names) {
        const std::string problem = plainNameProblem(n);
        if (!problem.empty()) refuse(n, "(from a Tonemap Extension) is not a plain file name (" + problem + ")");
        for (const PlannedOutput& o : out)
            if (fs::path(o.path).filename() == n) refuse(n, "is used by two Tonemap blocks");
        out.push_back({(dir / n).string(), "output '" + n + "'"});
    }
    return out;
}

}  // namespace

int cmdTonemap(int argc, char** argv) {
    TonemapArgs a = parseTonemapArgs(argc, argv);
    if (a.help) {
        std::fputs(kTonemapHelp, stdout);
        return 0;
    }
    const std::string outDir = fs::path(a.outPath).parent_path().empty() ? "." : fs::path(a.outPath).parent_path().string();
    std::unique_ptr<Scene> scene;
    if (!a.scenePath.empty()) scene = std::make_unique<Scene>(loadScene(a.scenePath));
    std::vector<TonemapSettings> settings = sceneBlocks(a, scene.get());
    applyOptions(a, settings);
    const std::vector<PlannedOutput> outs = planTonemapOutputs(a.outPath, settings);
    checkOutputDirectory(outDir);
    std::vector<std::string> inputs = {a.in};
    if (scene) {
        const std::vector<std::string> si = sceneInputs(*scene);
        inputs.insert(inputs.end(), si.begin(), si.end());
    }
    checkOutputsAreNotInputs(outs, inputs, "tonemap");
    const bool floatOut = lowerExtension(a.outPath) == ".exr";

    ImageRGB img = readImage(a.in);
    DeviceContext dc(selectDevices(a.deviceSpec).front());
    TonemapDevice tm(dc);
    tm.upload(img);
    std::vector<std::vector<unsigned char>> pngs;
    std::vector<ImageRGB> floats;
    for (const TonemapSettings& s : settings) {
        TonemapDeviceResult r = tm.map(s, floatOut);
        if (verbose())
            info(std::string(tmoKindName(s.op)) + ": log-average " + std::to_string(r.stats.logAverage) + ", scale " +
                 std::to_string(r.stats.scale) +
                 (r.stats.hasWhite ? ", L_white " + std::to_string(r.stats.whiteL) + " (rank " +
                                         std::to_string(r.stats.whiteIndex) + ")"
                                   : std::string()));
        if (floatOut) {
            ImageRGB d;
            d.width = img.width;
            d.height = img.height;
            d.pixels = std::move(r.display);
            floats.push_back(std::move(d));
        } else {
            pngs.push_back(std::move(r.rgb8));
        }
    }
    for (size_t i = 0; i < settings.size(); ++i) {
        if (floatOut) writeExr(outs[i].path, floats[i]);
        else writePng8(outs[i].path, img.width, img.height, pngs[i]);
        std::fprintf(stderr, "wrote %s\n", outs[i].path.c_str());
    }
    return 0;
}

}  // namespace clrt
