// libFuzzer target: readPly on arbitrary bytes. clrt::Error is accepted; anything else is a bug.
// A mesh that loads must have every index within its vertex array.
#include <cstdint>
#include <cstdlib>

#include "fuzz_common.h"
#include "scene/ply_reader.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string path = clrt::fuzz::writeInput(data, size, "mesh.ply");
    try {
        clrt::MeshData m = clrt::readPly(path);
        if (m.indices.size() % 3 != 0) std::abort();
        for (int i : m.indices)
            if (i < 0 || size_t(i) >= m.positions.size()) std::abort();
        if (!m.normals.empty() && m.normals.size() != m.positions.size()) std::abort();
        if (!m.uvs.empty() && m.uvs.size() != m.positions.size()) std::abort();
    } catch (const clrt::Error&) {
    }
    return 0;
}
