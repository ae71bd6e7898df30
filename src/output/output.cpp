// output.cpp — camera outputs (.png / .exr + tone-mapped .png) (see output.h). Tone mapping runs on the OpenCL device through TonemapDevice while the EXR is
// written on a second thread; all files of a camera are renamed into place together at the end.
#include "output/output.h"

#include <cctype>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <functional>
#include <set>
#include <thread>
#include <utility>

#include "output/tonemap_device.h"
#include "util/error.h"

namespace clrt {
namespace fs = std::filesystem;

namespace {

std::string formatSeconds(double s) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3f", s);
    return buf;
}

}  // namespace

std::string plainNameProblem(const std::string& name) {
    if (name.empty()) return "it is empty";
    if (name.size() > 200) return "it is longer than 200 bytes";
    if (name[0] == '.') return "it starts with '.'";
    for (unsigned char c : name) {
        if (c == '/' || c == '\\') return "it contains a directory separator";
        if (c < 0x20 || c == 0x7f) return "it contains a control character";
    }
    return "";
}

std::string lowerExtension(const std::string& name) {
    std::string ext = fs::path(name).extension().string();
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

std::vector<std::string> tonemapPngPaths(const std::string& hdrPath, const std::vector<TonemapSettings>& blocks) {
    fs::path p(hdrPath);
    const std::string stem = (p.parent_path() / p.stem()).string();
    std::vector<std::string> out;
    std::set<std::string> taken = {hdrPath};
    for (size_t i = 0; i < blocks.size(); ++i) {
        std::string suffix = blocks[i].extension;
        if (suffix.empty() && blocks.size() > 1) suffix = std::string("_") + tmoKindName(blocks[i].op);
        std::string path = stem + suffix + ".png";
        if (taken.count(path)) {
            std::string alt = stem + suffix + "_" + std::to_string(i + 1) + ".png";
            warnOnce(path + ": name used by an earlier Tonemap block; writing " + alt);
            path = alt;
        }
        taken.insert(path);
        out.push_back(path);
    }
    return out;
}

namespace {

// The 8-bit RGB of each Tonemap block of `cam`, tone-mapped on the device; `lap` times the stages (-v).
std::vector<std::vector<unsigned char>> tonemapCamera(const Camera& cam, const ImageRGB& radiance,
                                                      const OutputOptions& opts, DeviceContext& dc,
                                                      const std::function<void(const std::string&)>& lap) {
    std::vector<std::vector<unsigned char>> pngs;
    if (cam.tonemaps.empty()) return pngs;
    TonemapDevice tm(dc);
    lap("tone-map program");
    tm.upload(radiance);
    for (TonemapSettings s : cam.tonemaps) {
        s.truncate = opts.tonemapTruncate;
        TonemapDeviceResult r = tm.map(s);
        if (verbose())
            info(cam.imageName + ": " + tmoKindName(s.op) + " log-average " + std::to_string(r.stats.logAverage) +
                 (r.stats.hasWhite ? ", L_white " + std::to_string(r.stats.whiteL) : std::string()));
        pngs.push_back(std::move(r.rgb8));
    }
    lap("tone mapping");
    return pngs;
}

// Half or float channels and the header attributes of a render's EXR.
ExrWriteOptions exrOptions(const OutputOptions& opts, DeviceContext& dc) {
    ExrWriteOptions eo;
    eo.half = opts.exrHalf;
    eo.attributes["renderer"] = "clrt";
    eo.attributes["spp"] = std::to_string(opts.spp);
    eo.attributes["renderTime"] = formatSeconds(opts.renderSeconds) + " s";
    eo.attributes["device"] = opts.deviceName.empty() ? dc.info().name : opts.deviceName;
    if (!opts.partial.empty()) eo.attributes["partial"] = opts.partial;
    for (const auto& kv : opts.attributes) eo.attributes[kv.first] = kv.second;
    return eo;
}

// Renames each (temporary, final path) into place in order, appending the final paths to `written`;
// with `error` set, or on a failure, removes every temporary not yet renamed and throws.
void commitOutputs(const std::vector<std::pair<std::string, std::string>>& commits, const std::exception_ptr& error,
                   std::vector<std::string>& written) {
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
}

// The final paths of the tone-mapped PNGs of an EXR output, each name checked to be a plain file name.
std::vector<std::string> tonemapOutputPaths(const Camera& cam, const OutputOptions& opts) {
    std::vector<std::string> pngPaths;
    for (const std::string& name : tonemapPngPaths(cam.imageName, cam.tonemaps)) {
        if (!plainNameProblem(name).empty()) throw Error(name + ": not a plain file name (Tonemap Extension)");
        pngPaths.push_back((fs::path(opts.outDir) / name).string());
    }
    return pngPaths;
}

// A camera's EXR and tone-mapped PNGs, complete in their temporaries but not renamed into place.
struct UncommittedOutputs {
    std::string exrTmp;                // "" if the EXR failed
    std::vector<std::string> pngTmps;  // of the PNGs written, in pngPaths order
    std::exception_ptr error;          // the first failure: tone mapping, else the EXR, else a PNG
};

// The EXR does not depend on the tone mapping: it is written on its own thread (which compresses
// its chunks on all cores, see writeExr) while this one tone-maps on the device and encodes the
// PNGs. Every file goes to its temporary sibling first (the caller renames them when all are complete).
UncommittedOutputs writeExrOutputsUncommitted(const Camera& cam, const ImageRGB& radiance, const OutputOptions& opts,
                                              DeviceContext& dc, const std::string& exrPath,
                                              const std::vector<std::string>& pngPaths) {
    using Clock = std::chrono::steady_clock;
    auto seconds = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
    auto t0 = Clock::now();
    const std::function<void(const std::string&)> lap = [&](const std::string& what) {  // -v: where the output stage spends its time
        auto t1 = Clock::now();
        info("output: " + what + " " + std::to_string(seconds(t0, t1)) + " s");
        t0 = t1;
    };
    const ExrWriteOptions eo = exrOptions(opts, dc);
    UncommittedOutputs u;
    std::exception_ptr exrError;
    Clock::time_point exrStart = Clock::now(), exrEnd = exrStart;
    std::thread exrThread([&] {
        try {
            u.exrTmp = writeExrUncommitted(exrPath, radiance, eo);
        } catch (...) {
            exrError = std::current_exception();
        }
        exrEnd = Clock::now();
    });

    try {
        std::vector<std::vector<unsigned char>> pngs = tonemapCamera(cam, radiance, opts, dc, lap);
        try {
            for (size_t i = 0; i < pngs.size(); ++i)
                u.pngTmps.push_back(writePng8Uncommitted(pngPaths[i], radiance.width, radiance.height, pngs[i]));
            if (!pngs.empty()) lap("PNG");
        } catch (...) {
            exrThread.join();
            u.error = exrError ? exrError : std::current_exception();
        }
    } catch (...) {
        u.error = std::current_exception();
    }
    if (exrThread.joinable()) exrThread.join();
    if (!u.error) u.error = exrError;
    const double waited = seconds(t0, Clock::now());
    if (!u.error)
        info("output: EXR " + std::to_string(seconds(exrStart, exrEnd)) + " s (on its own thread; waited " +
             std::to_string(waited) + " s for it)");
    return u;
}

// Test hook (tests/test_cli_output.cpp): with CLRT_TEST_STALL_OUTPUT set, wait here, temporaries
// complete but not renamed, until a signal ends the process; the test checks that none is left behind.
void stallIfTestAsks() {
    if (!std::getenv("CLRT_TEST_STALL_OUTPUT")) return;
    std::fprintf(stderr, "output: stalled before the rename (CLRT_TEST_STALL_OUTPUT)\n");
    std::fflush(stderr);
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
}

}  // namespace

std::vector<std::string> writeCameraOutputs(const Camera& cam, const ImageRGB& radiance, const OutputOptions& opts,
                                            DeviceContext& dc) {
    if (!fs::is_directory(opts.outDir)) throw Error(opts.outDir + ": output directory does not exist", ExitCode::Output);
    // The CLI refuses bad names before rendering (src/cli/output_names.h); checked again here so that
    // no caller can write outside outDir.
    const std::string ext = lowerExtension(cam.imageName);
    if (!plainNameProblem(cam.imageName).empty() || (ext != ".png" && ext != ".exr"))
        throw Error(cam.imageName + ": not a plain .png or .exr file name");
    const std::string out = (fs::path(opts.outDir) / cam.imageName).string();
    std::vector<std::string> written;
    if (ext == ".png") {
        writePngClamped(out, radiance, opts.truncatePng);
        written.push_back(out);
        return written;
    }
    const std::vector<std::string> pngPaths = tonemapOutputPaths(cam, opts);
    // Nothing is renamed into place before every file is complete, so a device or write failure
    // changes none of the outputs.
    const UncommittedOutputs u = writeExrOutputsUncommitted(cam, radiance, opts, dc, out, pngPaths);
    if (!u.error) stallIfTestAsks();
    // Commit: EXR first, then the PNGs.
    std::vector<std::pair<std::string, std::string>> commits;  // (temporary, final path)
    if (!u.exrTmp.empty()) commits.emplace_back(u.exrTmp, out);
    for (size_t i = 0; i < u.pngTmps.size(); ++i) commits.emplace_back(u.pngTmps[i], pngPaths[i]);
    commitOutputs(commits, u.error, written);
    return written;
}

}  // namespace clrt
