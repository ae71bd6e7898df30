// Warning and verbose-message sinks (see error.h).
#include "util/error.h"

#include <cstdio>
#include <mutex>
#include <set>

namespace clrt {
namespace {
std::mutex gMutex;
std::set<std::string> gSeen;
bool gVerbose = false;
}  // namespace

void warn(const std::string& msg) {
    std::lock_guard<std::mutex> lock(gMutex);
    std::fprintf(stderr, "warning: %s\n", msg.c_str());
}

void warnOnce(const std::string& msg) {
    std::lock_guard<std::mutex> lock(gMutex);
    if (gSeen.insert(msg).second) std::fprintf(stderr, "warning: %s\n", msg.c_str());
}

void setVerbose(bool v) { gVerbose = v; }
bool verbose() { return gVerbose; }
void info(const std::string& msg) {
    if (gVerbose) std::fprintf(stderr, "%s\n", msg.c_str());
}
}  // namespace clrt
