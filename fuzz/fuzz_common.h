// Shared helpers of the libFuzzer targets: the readers take file paths, so every input is written to
// one file per process before the reader runs. By default that file lies in a private temporary
// folder (mkdtemp, removed at exit). With CLRT_FUZZ_INPUT_DIR set (scripts/fuzz.sh --gate sets it to
// "." and runs each target in a scratch folder of its own), inputs go there instead, so the path the
// readers see ("./scene.xml") is the same on every machine and run: no random or machine-specific
// bytes reach the comparisons libFuzzer learns from, which keeps a fixed-seed run repeatable.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

namespace clrt::fuzz {

inline const std::string& tempDir() {
    static std::string dir = [] {
        if (const char* given = std::getenv("CLRT_FUZZ_INPUT_DIR"); given && *given) return std::string(given);
        std::string tmpl = "/tmp/clrt-fuzz-XXXXXX";
        if (!mkdtemp(tmpl.data())) std::abort();
        std::string d = tmpl;
        static std::string toRemove = d;
        std::atexit([] { std::system(("rm -rf '" + toRemove + "'").c_str()); });
        return d;
    }();
    return dir;
}

// Writes the input to <tempDir>/<name> and returns that path.
inline std::string writeInput(const uint8_t* data, size_t size, const std::string& name) {
    std::string path = tempDir() + "/" + name;
    FILE* f = std::fopen(path.c_str(), "wb");
    if (!f) std::abort();
    if (size && std::fwrite(data, 1, size, f) != size) std::abort();
    std::fclose(f);
    return path;
}

}  // namespace clrt::fuzz
