// interrupt.cpp — the signal-waiting thread (see interrupt.h).
#include "cli/interrupt.h"

#include <csignal>
#include <cstdio>
#include <cstring>
#include <pthread.h>
#include <thread>
#include <unistd.h>

#include "image/image.h"

namespace clrt {

namespace {

std::atomic<bool> gStop{false};
std::atomic<bool> gGraceful{false};
std::atomic<int> gSignal{0};
std::atomic<const char*> gExitNote{nullptr};

const char* sigName(int sig) { return sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "SIGINT"; }

[[noreturn]] void exitNow(int sig, const char* why) {
    removeTemporariesForExit();
    if (const char* note = gExitNote.load())
        std::fprintf(stderr, "\n%s (%s)\n", note, sigName(sig));
    else
        std::fprintf(stderr, "\nclrt: %s (%s); no temporary file left behind\n", why, sigName(sig));
    std::fflush(stderr);
    _exit(128 + sig);
}

void waitForSignals(sigset_t set) {
    for (;;) {
        int sig = 0;
        if (sigwait(&set, &sig) != 0) continue;
        if (!gGraceful.load() || gStop.load())
            exitNow(sig, gStop.load() ? "interrupted again: exiting at once" : "interrupted");
        gSignal.store(sig);
        gStop.store(true);
        std::fprintf(stderr, "\nclrt: interrupted: finishing the current pass and writing the partial image "
                             "(interrupt again to quit at once)\n");
        std::fflush(stderr);
    }
}

}  // namespace

void installInterruptHandling() {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);  // the terminal closed: like SIGTERM, nothing half-written is left
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::thread(waitForSignals, set).detach();
}

void setGracefulInterrupt(bool graceful) { gGraceful.store(graceful); }
const std::atomic<bool>& stopRequested() { return gStop; }
int stopSignal() { return gSignal.load(); }
void setImmediateExitNote(const char* line) { gExitNote.store(line); }

}  // namespace clrt
