// interrupt.h — SIGINT/SIGTERM/SIGHUP for the CLI. The signals are blocked in every thread and taken by one
// thread that waits for them (sigwait), so what happens on a signal is ordinary code, not a signal
// handler. Immediate mode (the default): the first signal exits at once. Graceful mode (while a
// render runs): the first signal only sets the stop flag, and the render finishes its current pass
// and writes what it has; a second signal exits at once. Every exit removes the temporary files in
// flight (removeTemporariesForExit) and exits with status 128 + signal number.
#pragma once
#include <atomic>

namespace clrt {

// Call first in main(), before any thread is created (threads inherit the blocked signal mask).
void installInterruptHandling();
void setGracefulInterrupt(bool graceful);
// Set by the first signal in graceful mode.
const std::atomic<bool>& stopRequested();
// The signal that set stopRequested (0 if none).
int stopSignal();
// A line printed instead of the usual note when a signal ends the process at once (an MPI rank that
// mpirun ends because another rank failed). Set it before any signal may arrive.
void setImmediateExitNote(const char* line);

}  // namespace clrt
