// merge_cmd.cpp — `clrt merge`: reads the part files' headers, checks that they come from one render
// (render identity, spp, seed, image size, tile size) and that each camera's parts cover every tile
// exactly once, then writes each camera's outputs as `clrt render` would (same pixels, so the same
// PNG bytes and EXR floats; tone mapping on the device). Any problem is one error line naming a file,
// found before anything is written.
#include "cli/merge_cmd.h"

#include <cstdio>
#include <cstring>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "cl/devices.h"
#include "cl/program.h"
#include "cli/args.h"
#include "cli/output_names.h"
#include "dist/part_file.h"
#include "dist/tiles.h"
#include "output/output.h"
#include "util/error.h"

namespace clrt {

namespace {

const char* kMergeHelp =
    "usage: clrt merge PART.exr... [-o OUTDIR] [--device SPEC] [-v]\n"
    "\n"
    "Puts together the part files of `clrt render SCENE --part K/N` (one per part and camera, named\n"
    "<ImageName>.part<K>of<N>.exr) and writes each camera's outputs into OUTDIR (default: the current\n"
    "directory), as the whole render would: the same pixels, the tone-mapped PNGs of its Tonemap\n"
    "blocks, the same --ldr-quantize and --exr-half. The parts must come from the same scene files,\n"
    "options, spp and seed, and together cover every tile of each camera exactly once.\n"
    "\n"
    "options:\n"
    "  -o, --output DIR   output directory (default: the current directory); must exist\n"
    "  --device SPEC      OpenCL device for tone mapping (as in clrt render)\n"
    "  -v, --verbose      print details\n";

struct Part {
    std::string path;
    PartHeader h;
};

// The parts of one camera: same size, tile size, ImageName; every tile in exactly one part.
void checkCoverage(const std::vector<const Part*>& parts) {
    const Part& a = *parts.front();
    const TileGrid grid{size_t(a.h.width) * a.h.height, a.h.tilePixels};
    std::vector<const Part*> owner(grid.count(), nullptr);
    for (const Part* p : parts) {
        const std::string cam = "camera " + std::to_string(a.h.cameraId);
        if (p->h.width != a.h.width || p->h.height != a.h.height || p->h.tilePixels != a.h.tilePixels ||
            p->h.imageName != a.h.imageName)
            throw Error(p->path + ": " + cam + " is " + std::to_string(p->h.width) + "x" + std::to_string(p->h.height) +
                        " in tiles of " + std::to_string(p->h.tilePixels) + " pixels, but in " + a.path + " it is " +
                        std::to_string(a.h.width) + "x" + std::to_string(a.h.height) + " in tiles of " +
                        std::to_string(a.h.tilePixels));
        for (size_t t : p->h.tiles) {
            if (owner[t])
                throw Error(p->path + ": overlaps " + owner[t]->path + " (both hold tile " + std::to_string(t) + ", pixels " +
                            std::to_string(grid.first(t)) + "-" + std::to_string(grid.first(t) + grid.size(t) - 1) +
                            " of " + cam + ")");
            owner[t] = p;
        }
    }
    std::vector<size_t> missing;
    for (size_t t = 0; t < grid.count(); ++t)
        if (!owner[t]) missing.push_back(t);
    if (missing.empty()) return;
    std::set<int> given;
    for (const Part* p : parts) given.insert(p->h.part);
    std::string absent;
    for (int k = 1; k <= a.h.parts; ++k)
        if (!given.count(k)) absent += (absent.empty() ? "" : ", ") + std::to_string(k) + "/" + std::to_string(a.h.parts);
    std::string list = formatTileList(missing);
    if (list.size() > 60) list = list.substr(0, 60) + "...";
    throw Error(a.path + ": the parts of camera " + std::to_string(a.h.cameraId) + " miss tiles " + list + " of " +
                std::to_string(grid.count()) + (absent.empty() ? "" : " (part " + absent + " not given)"));
}

// The camera's image from its parts' tiles.
ImageRGB assemble(const std::vector<const Part*>& parts) {
    const PartHeader& h = parts.front()->h;
    ImageRGB img;
    img.width = h.width;
    img.height = h.height;
    img.isHdr = true;
    img.pixels.assign(size_t(h.width) * h.height * 3, 0.0f);
    const TileGrid grid{size_t(h.width) * h.height, h.tilePixels};
    for (const Part* p : parts) {
        ImageRGB part = readImage(p->path);
        if (part.width != h.width || part.height != h.height) throw Error(p->path + ": image size differs from its header");
        for (size_t t : p->h.tiles)
            std::memcpy(&img.pixels[grid.first(t) * 3], &part.pixels[grid.first(t) * 3], grid.size(t) * 3 * sizeof(float));
    }
    return img;
}

Camera cameraOf(const PartHeader& h) {
    Camera c;
    c.id = h.cameraId;
    c.width = h.width;
    c.height = h.height;
    c.numSamples = h.spp;
    c.imageName = h.imageName;
    c.tonemaps = h.tonemaps;
    return c;
}

}  // namespace

int cmdMerge(int argc, char** argv) {
    std::string outDir = ".", device;
    bool help = false, verboseFlag = false;
    const std::vector<std::string> paths = parseArgs(argc, argv, 2, {
        {{"-h", "--help"}, false, [&](const std::string&, const std::string&) { help = true; }, /*endsParsing=*/true},
        textOption({"-o", "--output"}, outDir),
        textOption({"--device"}, device),
        flagOption({"-v", "--verbose"}, verboseFlag),
    }, "merge");
    if (help) {
        std::fputs(kMergeHelp, stdout);
        return 0;
    }
    if (verboseFlag) setVerbose(true);
    if (paths.empty()) throw Error("merge: expected part files (see clrt merge --help)", ExitCode::Usage);
    checkOutputDirectory(outDir);

    std::vector<Part> parts;
    for (const std::string& p : paths) parts.push_back({p, readPartHeader(p)});
    // One render: the same identity, spp and seed everywhere; then per camera, in order of appearance.
    const Part& first = parts.front();
    std::vector<int> order;
    std::map<int, std::vector<const Part*>> byCamera;
    for (const Part& p : parts) {
        if (p.h.identity != first.h.identity)
            throw Error(p.path + ": from another render than " + first.path + " (scene '" + p.h.sceneFile + "' vs '" +
                        first.h.sceneFile + "': different scene files or options)");
        if (p.h.spp != first.h.spp || p.h.seed != first.h.seed)
            throw Error(p.path + ": rendered at spp " + std::to_string(p.h.spp) + " seed " + std::to_string(p.h.seed) +
                        ", but " + first.path + " at spp " + std::to_string(first.h.spp) + " seed " + std::to_string(first.h.seed));
        if (!byCamera.count(p.h.cameraId)) order.push_back(p.h.cameraId);
        byCamera[p.h.cameraId].push_back(&p);
    }
    std::vector<Camera> cams;
    for (int id : order) {
        checkCoverage(byCamera[id]);
        cams.push_back(cameraOf(byCamera[id].front()->h));
    }
    Scene named;  // only for the output-name checks' messages
    named.path = first.path;
    std::vector<const Camera*> camPtrs;
    for (const Camera& c : cams) camPtrs.push_back(&c);
    checkOutputsAreNotInputs(planRenderOutputs(named, camPtrs, outDir), paths, first.path);

    DeviceContext dc(selectDevices(device).front());
    for (size_t i = 0; i < cams.size(); ++i) {
        const std::vector<const Part*>& ps = byCamera[order[i]];
        OutputOptions oo;
        oo.outDir = outDir;
        oo.truncatePng = ps.front()->h.truncatePng;
        oo.exrHalf = ps.front()->h.exrHalf;
        oo.spp = ps.front()->h.spp;
        std::set<std::string> devices;
        for (const Part* p : ps) {
            oo.renderSeconds += p->h.renderSeconds;
            if (devices.insert(p->h.device).second) oo.deviceName += (oo.deviceName.empty() ? "" : ", ") + p->h.device;
        }
        for (const std::string& w : writeCameraOutputs(cams[i], assemble(ps), oo, dc))
            std::fprintf(stderr, "wrote %s (camera %d from %zu parts)\n", w.c_str(), cams[i].id, ps.size());
    }
    return 0;
}

}  // namespace clrt
