// Part files: header attributes written and read back (see part_file.h).
#include "dist/part_file.h"

#include <ImfHeader.h>
#include <ImfInputFile.h>
#include <ImfStringAttribute.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>

#include "dist/tiles.h"
#include "image/tonemap.h"
#include "util/error.h"

namespace clrt {

std::string partFileName(const std::string& imageName, int k, int n) {
    return imageName + ".part" + std::to_string(k) + "of" + std::to_string(n) + ".exr";
}

namespace {
std::string fmtFloat(float v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.9g", double(v));
    return buf;
}
// One Tonemap block as "tmo key burn saturation gamma srgb extension" (srgb 0/1; the extension last,
// may be empty).
std::string formatTonemap(const TonemapSettings& t) {
    return std::string(tmoKindName(t.op)) + " " + fmtFloat(t.key) + " " + fmtFloat(t.burnPercent) + " " +
           fmtFloat(t.saturation) + " " + fmtFloat(t.gamma) + " " + (t.srgb ? "1" : "0") + " " + t.extension;
}
TonemapSettings parseTonemap(const std::string& s, const std::string& what) {
    std::istringstream in(s);
    std::string op;
    int srgb = 0;
    TonemapSettings t;
    if (!(in >> op >> t.key >> t.burnPercent >> t.saturation >> t.gamma >> srgb) || (srgb != 0 && srgb != 1))
        throw Error(what + ": bad Tonemap attribute '" + s + "'");
    t.srgb = srgb == 1;
    t.op = parseTmoKind(op, what);
    std::string rest;
    std::getline(in, rest);
    t.extension = rest.empty() ? "" : rest.substr(1);
    return t;
}
long toLong(const std::map<std::string, std::string>& a, const std::string& key, const std::string& path, long lo, long hi) {
    auto it = a.find(key);
    if (it == a.end()) throw Error(path + ": not a clrt part file (no '" + key + "' attribute; made by clrt render --part K/N?)");
    char* end = nullptr;
    long v = std::strtol(it->second.c_str(), &end, 10);
    if (it->second.empty() || *end || v < lo || v > hi) throw Error(path + ": bad '" + key + "' attribute '" + it->second + "'");
    return v;
}
}  // namespace

void writePartFile(const std::string& path, const PartHeader& h, const ImageRGB& img) {
    ImageRGB out;
    out.width = img.width;
    out.height = img.height;
    out.isHdr = true;
    out.pixels.assign(img.pixels.size(), 0.0f);
    const TileGrid grid{size_t(img.width) * img.height, h.tilePixels};
    for (size_t t : h.tiles)
        std::copy(img.pixels.begin() + long(grid.first(t) * 3), img.pixels.begin() + long((grid.first(t) + grid.size(t)) * 3),
                  out.pixels.begin() + long(grid.first(t) * 3));
    ExrWriteOptions eo;
    auto& a = eo.attributes;
    a["renderer"] = "clrt";
    a["spp"] = std::to_string(h.spp);
    char secs[32];
    std::snprintf(secs, sizeof secs, "%.3f s", h.renderSeconds);
    a["renderTime"] = secs;
    a["device"] = h.device;
    a["clrtRender"] = h.identity;
    a["clrtSceneFile"] = h.sceneFile;
    a["clrtCamera"] = std::to_string(h.cameraId);
    a["clrtImageName"] = h.imageName;
    a["clrtSeed"] = std::to_string(h.seed);
    a["clrtTilePixels"] = std::to_string(h.tilePixels);
    a["clrtPart"] = std::to_string(h.part) + "/" + std::to_string(h.parts);
    a["clrtTiles"] = formatTileList(h.tiles);
    a["clrtLdrQuantize"] = h.truncatePng ? "floor" : "round";
    a["clrtExrHalf"] = h.exrHalf ? "1" : "0";
    a["clrtTonemaps"] = std::to_string(h.tonemaps.size());
    for (size_t i = 0; i < h.tonemaps.size(); ++i) a["clrtTonemap" + std::to_string(i)] = formatTonemap(h.tonemaps[i]);
    writeExr(path, out, eo);
}

PartHeader readPartHeader(const std::string& path) {
    std::map<std::string, std::string> a;
    int width = 0, height = 0;
    if (!std::filesystem::is_regular_file(path)) throw Error(path + ": no such part file");
    try {
        Imf::InputFile in(path.c_str());
        const Imf::Header& hd = in.header();
        for (auto it = hd.begin(); it != hd.end(); ++it)
            if (const auto* s = dynamic_cast<const Imf::StringAttribute*>(&it.attribute())) a[it.name()] = s->value();
        const Imath::Box2i dw = hd.dataWindow();
        width = dw.max.x - dw.min.x + 1;
        height = dw.max.y - dw.min.y + 1;
    } catch (const std::exception& e) {
        throw Error(path + ": not a readable OpenEXR part file (" + e.what() + ")");
    }
    PartHeader h;
    h.identity = a.count("clrtRender") ? a["clrtRender"] : "";
    if (h.identity.empty()) throw Error(path + ": not a clrt part file (no 'clrtRender' attribute; made by clrt render --part K/N?)");
    h.sceneFile = a["clrtSceneFile"];
    h.width = width;
    h.height = height;
    h.cameraId = int(toLong(a, "clrtCamera", path, -2147483647L, 2147483647L));
    h.imageName = a["clrtImageName"];
    h.spp = int(toLong(a, "spp", path, 1, 1L << 20));
    h.seed = uint32_t(toLong(a, "clrtSeed", path, 0, 2147483647L));
    h.tilePixels = size_t(toLong(a, "clrtTilePixels", path, 1, 1L << 30));
    if (std::sscanf(a["clrtPart"].c_str(), "%d/%d", &h.part, &h.parts) != 2 || h.part < 1 || h.part > h.parts)
        throw Error(path + ": bad 'clrtPart' attribute '" + a["clrtPart"] + "'");
    const TileGrid grid{size_t(width) * height, h.tilePixels};
    h.tiles = parseTileList(a["clrtTiles"], grid.count(), path);
    h.truncatePng = a["clrtLdrQuantize"] == "floor";
    h.exrHalf = a["clrtExrHalf"] == "1";
    const long n = toLong(a, "clrtTonemaps", path, 0, 64);
    for (long i = 0; i < n; ++i) h.tonemaps.push_back(parseTonemap(a["clrtTonemap" + std::to_string(i)], path));
    h.renderSeconds = std::atof(a["renderTime"].c_str());
    h.device = a["device"];
    return h;
}

}  // namespace clrt
