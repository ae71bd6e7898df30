// Shared helpers of the libFuzzer targets: the readers take file paths, so every input is written to
// one temporary file per process (in a private temporary folder) before the reader runs.
#pragma once
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <unistd.h>

namespace clrt::fuzz {

// A private folder for this process, created once (mkdtemp) and removed at exit.
inline const std::string& tempDir() {
    static std::string dir = [] {
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
