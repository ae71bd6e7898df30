// libFuzzer target: loadScene on arbitrary bytes (XML or JSON, chosen by content as in clrt). Any
// clrt::Error is an accepted outcome; a crash, sanitizer report, hang or other exception is a bug.
#include <cstdint>
#include <cstdio>
#include <exception>

#include "fuzz_common.h"
#include "scene/scene_loader.h"
#include "util/error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    std::string path = clrt::fuzz::writeInput(data, size, "scene.xml");
    try {
        clrt::Scene s = clrt::loadScene(path);
        (void)s;
    } catch (const clrt::Error&) {
    }
    return 0;
}
