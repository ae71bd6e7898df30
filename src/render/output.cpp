// output.cpp — camera outputs (.png / .exr + tone-mapped .png) and the `clrt tonemap` subcommand
// (see output.h). Tone mapping runs on the OpenCL device through TonemapDevice while the EXR is
// written on a second thread; all files of a camera are renamed into place together at the end.
#include "render/output.h"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <set>
#include <thread>
#include <utility>

#include "cl/devices.h"
#include "render/tonemap_device.h"
#include "scene/scene_loader.h"
#include "util/error.h"

namespace clrt {
namespace fs = std::filesystem;

namespace {

std::string lowerExt(const fs::path& p) {
    std::string ext = p.extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::string formatSeconds(double s) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f", s);
    return buf;
}

}  // namespace

TonemapSettings tonemapSettingsFrom(const Tonemap& t) {
    TonemapSettings s;
    s.op = t.op;
    s.key = t.key;
    s.burnPercent = t.burnPercent;
    s.saturation = t.saturation;
    s.gamma = t.gamma;
    return s;
}

std::vector<std::string> tonemapPngPaths(const std::string& hdrPath, const std::vector<Tonemap>& blocks) {
    fs::path p(hdrPath);
    const std::string stem = (p.parent_path() / p.stem()).string();
    std::vector<std::string> out;
    std::set<std::string> taken = {hdrPath};
    for (size_t i = 0; i < blocks.size(); ++i) {
        std::string suffix = blocks[i].extension;
        if (suffix.empty() && blocks.size() > 1) suffix = std::string("_") + tmoKindName(tonemapSettingsFrom(blocks[i]).op);
        std::string path = stem + suffix + ".png";
        if (taken.count(path)) {
            std::string alt = stem + suffix + "_" + std::to_string(i + 1) + ".png";
            warn(path + ": name used by an earlier Tonemap block; writing " + alt);
            path = alt;
        }
        taken.insert(path);
        out.push_back(path);
    }
    return out;
}

std::vector<std::string> writeCameraOutputs(const Camera& cam, const ImageRGB& radiance, const OutputOptions& opts,
                                            DeviceContext& dc) {
    if (!fs::is_directory(opts.outDir)) throw Error(opts.outDir + ": output directory does not exist", ExitCode::Output);
    const fs::path out = fs::path(opts.outDir) / fs::path(cam.imageName).filename();
    const std::string ext = lowerExt(out);
    std::vector<std::string> written;
    if (ext != ".exr") {
        if (ext != ".png") warnOnce(cam.imageName + ": unknown image extension; writing PNG data");
        writePngClamped(out.string(), radiance, opts.truncatePng);
        written.push_back(out.string());
        return written;
    }

    // The EXR does not depend on the tone mapping: it is written on its own thread (which compresses
    // its chunks on all cores, see writeExr) while this one tone-maps on the device and encodes the
    // PNGs. Every file goes to its temporary sibling first and nothing is renamed into place before all
    // of them are complete, so a device or write failure changes none of the outputs.
    const std::vector<std::string> pngPaths = tonemapPngPaths(out.string(), cam.tonemaps);
    using Clock = std::chrono::steady_clock;
    auto seconds = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
    auto t0 = Clock::now();
    auto lap = [&](const std::string& what) {  // -v: where the output stage spends its time
        auto t1 = Clock::now();
        info("output: " + what + " " + std::to_string(seconds(t0, t1)) + " s");
        t0 = t1;
    };
    ExrWriteOptions eo;
    eo.half = opts.exrHalf;
    eo.attributes["renderer"] = "clrt";
    eo.attributes["spp"] = std::to_string(opts.spp);
    eo.attributes["renderTime"] = formatSeconds(opts.renderSeconds) + " s";
    eo.attributes["device"] = opts.deviceName.empty() ? dc.info().name : opts.deviceName;
    const std::string exrPath = out.string();
    std::string exrTmp;
    std::exception_ptr exrError;
    Clock::time_point exrStart = Clock::now(), exrEnd = exrStart;
    std::thread exrThread([&] {
        try {
            exrTmp = writeExrUncommitted(exrPath, radiance, eo);
        } catch (...) {
            exrError = std::current_exception();
        }
        exrEnd = Clock::now();
    });

    std::exception_ptr error;  // the first failure: tone mapping, else the EXR, else a PNG
    std::vector<std::string> pngTmps;
    try {
        std::vector<std::vector<unsigned char>> pngs;
        if (!cam.tonemaps.empty()) {
            TonemapDevice tm(dc);
            lap("tone-map program");
            tm.upload(radiance);
            for (const Tonemap& t : cam.tonemaps) {
                TonemapSettings s = tonemapSettingsFrom(t);
                s.truncate = opts.tonemapTruncate;
                TonemapDeviceResult r = tm.map(s);
                if (verbose())
                    info(cam.imageName + ": " + tmoKindName(s.op) + " log-average " + std::to_string(r.stats.logAverage) +
                         (r.stats.hasWhite ? ", L_white " + std::to_string(r.stats.whiteL) : std::string()));
                pngs.push_back(std::move(r.rgb8));
            }
            lap("tone mapping");
        }
        try {
            for (size_t i = 0; i < pngs.size(); ++i)
                pngTmps.push_back(writePng8Uncommitted(pngPaths[i], radiance.width, radiance.height, pngs[i]));
            if (!pngs.empty()) lap("PNG");
        } catch (...) {
            exrThread.join();
            error = exrError ? exrError : std::current_exception();
        }
    } catch (...) {
        error = std::current_exception();
    }
    if (exrThread.joinable()) exrThread.join();
    if (!error) error = exrError;
    const double waited = seconds(t0, Clock::now());
    if (!error)
        info("output: EXR " + std::to_string(seconds(exrStart, exrEnd)) + " s (on its own thread; waited " +
             std::to_string(waited) + " s for it)");

    // Commit: EXR first, then the PNGs; on any failure remove every temporary not yet renamed.
    std::vector<std::pair<std::string, std::string>> commits;  // (temporary, final path)
    if (!exrTmp.empty()) commits.emplace_back(exrTmp, exrPath);
    for (size_t i = 0; i < pngTmps.size(); ++i) commits.emplace_back(pngTmps[i], pngPaths[i]);
    size_t done = 0;
    try {
        if (error) std::rethrow_exception(error);
        for (; done < commits.size(); ++done) {
            commitTemporary(commits[done].first, commits[done].second);
            written.push_back(commits[done].second);
        }
    } catch (...) {
        for (size_t i = done; i < commits.size(); ++i) std::remove(commits[i].first.c_str());
        throw;
    }
    return written;
}

// ---- clrt tonemap ------------------------------------------------------------------------------

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
    "                        the display values (gamma applied, in [0,1]) as float, not quantised\n"
    "  --tmo NAME            photographic (Reinhard 2002, global; default), aces (Narkowicz's fit)\n"
    "                        or filmic (Hable's Uncharted 2 curve, white point 11.2)\n"
    "  --key K               key value a: L = a·Y / log-average(Y) (default 0.18)\n"
    "  --burn P              photographic: percentage of pixels burnt out to white (default 1;\n"
    "                        0: no white point)\n"
    "  --saturation S        RGBo = Yo·(RGB/Y)^S (default 1)\n"
    "  --gamma G             8-bit value of c is 255·c^(1/G) (default 2.2)\n"
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

float parseFloatArg(const std::string& opt, const std::string& v) {
    char* end = nullptr;
    errno = 0;
    float x = std::strtof(v.c_str(), &end);
    if (v.empty() || *end != '\0' || errno != 0 || !std::isfinite(x))
        throw Error(opt + ": expected a number, got '" + v + "'", ExitCode::Usage);
    return x;
}

}  // namespace

int cmdTonemap(int argc, char** argv) {
    std::vector<std::string> positional;
    std::string outPath, scenePath, cameraId, deviceSpec;
    bool haveTmo = false, haveKey = false, haveBurn = false, haveSat = false, haveGamma = false, haveDelta = false;
    TonemapSettings over;
    bool truncate = true;
    for (int i = 2; i < argc; ++i) {
        std::string s = argv[i];
        auto value = [&]() -> std::string {
            if (i + 1 >= argc) throw Error(s + ": missing value", ExitCode::Usage);
            return argv[++i];
        };
        if (s == "-h" || s == "--help") {
            std::fputs(kTonemapHelp, stdout);
            return 0;
        } else if (s == "-o" || s == "--output") outPath = value();
        else if (s == "--tmo") { over.op = parseTmoKind(value()); haveTmo = true; }
        else if (s == "--key") { over.key = parseFloatArg(s, value()); haveKey = true; }
        else if (s == "--burn") { over.burnPercent = parseFloatArg(s, value()); haveBurn = true; }
        else if (s == "--saturation") { over.saturation = parseFloatArg(s, value()); haveSat = true; }
        else if (s == "--gamma") { over.gamma = parseFloatArg(s, value()); haveGamma = true; }
        else if (s == "--quantize") {
            std::string v = value();
            if (v != "round" && v != "floor") throw Error("--quantize: expected round or floor, got '" + v + "'", ExitCode::Usage);
            truncate = v == "floor";
        }
        else if (s == "--delta") { over.delta = parseFloatArg(s, value()); haveDelta = true; }
        else if (s == "--scene") scenePath = value();
        else if (s == "--camera") cameraId = value();
        else if (s == "--device") deviceSpec = value();
        else if (s == "-v" || s == "--verbose") setVerbose(true);
        else if (!s.empty() && s[0] == '-') throw Error("unknown option '" + s + "' (see clrt tonemap --help)", ExitCode::Usage);
        else positional.push_back(s);
    }
    if (positional.size() != 1) throw Error("tonemap: expected exactly one input image (see clrt tonemap --help)", ExitCode::Usage);
    if (!cameraId.empty() && scenePath.empty()) throw Error("tonemap: --camera needs --scene", ExitCode::Usage);
    const std::string in = positional[0];
    if (outPath.empty()) outPath = (fs::path(in).parent_path() / fs::path(in).stem()).string() + ".png";
    const bool floatOut = lowerExt(outPath) == ".exr";
    if (!floatOut && lowerExt(outPath) != ".png") warnOnce(outPath + ": output is written as PNG data");

    // The blocks to apply: the scene camera's, or one default block; then the explicit options.
    std::vector<Tonemap> blocks;
    if (!scenePath.empty()) {
        Scene scene = loadScene(scenePath);
        const Camera* cam = nullptr;
        for (const Camera& c : scene.cameras)
            if (cameraId.empty() ? scene.cameras.size() == 1 : std::to_string(c.id) == cameraId) cam = &c;
        if (!cam)
            throw Error(scenePath + (cameraId.empty() ? ": the scene has " + std::to_string(scene.cameras.size()) +
                                                            " cameras; choose one with --camera"
                                                      : ": no camera with id " + cameraId));
        blocks = cam->tonemaps;
        if (blocks.empty()) throw Error(scenePath + ": camera " + std::to_string(cam->id) + " has no Tonemap block");
    } else {
        blocks.resize(1);
    }
    std::vector<TonemapSettings> settings;
    for (Tonemap& b : blocks) {
        TonemapSettings s = tonemapSettingsFrom(b);
        if (haveTmo) s.op = over.op;
        if (haveKey) s.key = over.key;
        if (haveBurn) s.burnPercent = over.burnPercent;
        if (haveSat) s.saturation = over.saturation;
        if (haveGamma) s.gamma = over.gamma;
        if (haveDelta) s.delta = over.delta;
        s.truncate = truncate;
        validateTonemapSettings(s, "tonemap");
        settings.push_back(s);
        if (haveTmo) b.op = s.op;
    }
    // With several blocks, -o gives the stem the block names are added to.
    std::vector<std::string> outs = blocks.size() == 1 ? std::vector<std::string>{outPath} : tonemapPngPaths(outPath, blocks);
    if (floatOut && blocks.size() > 1)
        for (std::string& o : outs) o = fs::path(o).replace_extension(".exr").string();
    const fs::path outDir = fs::path(outPath).parent_path();
    if (!outDir.empty() && !fs::is_directory(outDir))
        throw Error(outPath + ": output directory '" + outDir.string() + "' does not exist", ExitCode::Output);

    ImageRGB img = readImage(in);
    DeviceContext dc(selectDevices(deviceSpec).front());
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
        if (floatOut) writeExr(outs[i], floats[i]);
        else writePng8(outs[i], img.width, img.height, pngs[i]);
        std::fprintf(stderr, "wrote %s\n", outs[i].c_str());
    }
    return 0;
}

}  // namespace clrt
