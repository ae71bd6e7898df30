// Tile grid, part tile sets, tile lists as text, render identity (see tiles.h).
#include "dist/tiles.h"

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <iterator>

#include "cl/embedded_kernels.h"
#include "util/error.h"

namespace clrt {

size_t defaultTilePixels(size_t numPixels) {
    return std::clamp<size_t>((numPixels + 63) / 64, 4096, 65536);
}

std::vector<size_t> partTiles(size_t tileCount, int k, int n) {
    std::vector<size_t> out;
    for (size_t t = size_t(k - 1); t < tileCount; t += size_t(n)) out.push_back(t);
    return out;
}

std::string formatTileList(const std::vector<size_t>& tiles) {
    std::string s;
    for (size_t i = 0; i < tiles.size();) {
        size_t j = i;
        while (j + 1 < tiles.size() && tiles[j + 1] == tiles[j] + 1) ++j;
        if (!s.empty()) s += ',';
        s += std::to_string(tiles[i]);
        if (j > i) s += "-" + std::to_string(tiles[j]);
        i = j + 1;
    }
    return s;
}

std::vector<size_t> parseTileList(const std::string& text, size_t limit, const std::string& what) {
    std::vector<size_t> out;
    std::vector<bool> seen(limit, false);
    auto bad = [&](const std::string& why) { return Error(what + ": bad tile list '" + text.substr(0, 80) + "': " + why); };
    size_t at = 0;
    while (at < text.size()) {
        size_t end = text.find(',', at);
        if (end == std::string::npos) end = text.size();
        const std::string item = text.substr(at, end - at);
        char* p = nullptr;
        unsigned long long a = std::strtoull(item.c_str(), &p, 10), b = a;
        if (p == item.c_str()) throw bad("not a number");
        if (*p == '-') {
            const char* q = p + 1;
            b = std::strtoull(q, &p, 10);
            if (p == q) throw bad("not a range");
        }
        if (*p != '\0' || b < a) throw bad("not a range");
        if (b >= limit) throw bad("tile " + std::to_string(b) + " is beyond the image's " + std::to_string(limit) + " tiles");
        for (unsigned long long t = a; t <= b; ++t) {
            if (seen[t]) throw bad("tile " + std::to_string(t) + " listed twice");
            seen[t] = true;
            out.push_back(size_t(t));
        }
        at = end + 1;
    }
    std::sort(out.begin(), out.end());
    return out;
}

std::string hexKey(uint64_t v) {
    char buf[17];
    std::snprintf(buf, sizeof buf, "%016llx", (unsigned long long)v);
    return buf;
}

std::string renderIdentity(const std::vector<std::string>& inputFiles, const std::string& options) {
    uint64_t h = fnv1a64(nullptr, 0);
    for (const std::string& path : inputFiles) {
        std::ifstream in(path, std::ios::binary);
        if (!in) throw Error(path + ": cannot read (hashing the render's inputs)");
        std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        const uint64_t size = bytes.size();
        h = fnv1a64(&size, sizeof size, h);
        h = fnv1a64(bytes.data(), bytes.size(), h);
    }
    for (const EmbeddedSource& s : embeddedKernelSources()) {
        h = fnv1a64(s.path, std::char_traits<char>::length(s.path), h);
        h = fnv1a64(s.text, std::char_traits<char>::length(s.text), h);
    }
    return hexKey(fnv1a64(options.data(), options.size(), h));
}

}  // namespace clrt
