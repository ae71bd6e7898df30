// Shared vertex data: <VertexData> (x y z per vertex) and <TexCoordData> (u v per vertex), as text or,
// with a binaryFile attribute, as a little-endian file of float32 records (Walker::binaryWords). Several
// elements add up in document order. Objects name the vertices by index (vertexIndex below:
// 1-based unless <ZeroBasedIndexing>); read_objects.cpp copies what each mesh uses.
#include <cmath>
#include <cstring>

#include "scene/scene_walker.h"

namespace clrt::walker {
namespace {

// The numbers of n: its text, or the float32 words of its binaryFile (each finite).
std::vector<double> floatData(const Walker& w, const SceneNode& n, const char* records, size_t perRecord) {
    if (auto bf = n.attribute("binaryFile")) {
        auto words = w.binaryWords(n, *bf, records, perRecord);
        std::vector<double> out(words.size());
        for (size_t i = 0; i < out.size(); ++i) {
            float f;
            std::memcpy(&f, &words[i], 4);
            if (!std::isfinite(f)) fail(n, describe(n) + ": binaryFile '" + *bf + "' holds a non-finite value");
            out[i] = f;
        }
        return out;
    }
    return numbers(n);
}

}  // namespace

void readVertexData(Walker& w, const SceneNode& n) {
    auto v = floatData(w, n, "vertices", 3);
    if (v.size() % 3 != 0)
        fail(n, "<VertexData> has " + std::to_string(v.size()) + " values, not a multiple of 3");
    for (size_t i = 0; i < v.size(); i += 3) w.vertices.emplace_back(float(v[i]), float(v[i + 1]), float(v[i + 2]));
}

void readTexCoordData(Walker& w, const SceneNode& n) {
    auto v = floatData(w, n, "texture coordinates", 2);
    if (v.size() % 2 != 0)
        fail(n, "<TexCoordData> has " + std::to_string(v.size()) + " values, not a multiple of 2");
    for (size_t i = 0; i < v.size(); i += 2) w.texcoords.push_back(Vec2{float(v[i]), float(v[i + 1])});
}

int vertexIndex(const Walker& w, const SceneNode& n, const std::string& who, long raw, long offset) {
    long i = raw + offset - (w.zeroBased ? 0 : 1);
    if (i < 0 || i >= long(w.vertices.size()))
        fail(n, who + ": vertex index " + std::to_string(raw) +
                    (offset ? " (+ vertexOffset " + std::to_string(offset) + ")" : std::string()) +
                    " is out of range (VertexData has " + std::to_string(w.vertices.size()) + " vertices, " +
                    (w.zeroBased ? "0-based" : "1-based") + ")");
    return int(i);
}

}  // namespace clrt::walker
