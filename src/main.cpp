// clrt command line: dispatches `clrt devices`, `clrt render`, `clrt tonemap` and `clrt merge` to
// their commands in src/cli/ (render_cmd, tonemap_cmd, merge_cmd), starts MPI for `render` when an
// MPI launcher started the process, and turns every error into one line on stderr and its exit code
// (clrt::Error's own; 3 for OpenCL errors and host memory). Ctrl-C / SIGTERM: src/cli/interrupt.h.
#include <CL/opencl.hpp>

#include <cstdio>
#include <cstring>
#include <iostream>
#include <new>
#include <string>

#include "cl/devices.h"
#include "cli/interrupt.h"
#include "cli/merge_cmd.h"
#include "cli/render_cmd.h"
#include "cli/tonemap_cmd.h"
#include "dist/mpi_job.h"
#include "util/error.h"

using namespace clrt;

namespace {

const char* kMainHelp =
    "clrt — an OpenCL ray tracer for CENG795 scenes\n"
    "\n"
    "usage: clrt <command> [options]\n"
    "\n"
    "commands:\n"
    "  devices                 list every OpenCL platform/device with its index\n"
    "  render SCENE [options]  render every camera of SCENE (XML or JSON); see `clrt render --help`\n"
    "  tonemap IN.exr [options] tone-map an HDR image to PNG on the device; see `clrt tonemap --help`\n"
    "  merge PARTS... -o DIR   put together the parts of `clrt render --part K/N`; see `clrt merge --help`\n"
    "\n"
    "`mpirun -np N clrt render SCENE ...` renders one image over N MPI ranks (see `clrt render --help`).\n"
    "\n"
    "options:\n"
    "  -h, --help              this text\n"
    "\n"
    "exit codes: 0 ok, 1 usage, 2 bad input, 3 device failure, 4 output failure,\n"
    "            130/143/129 interrupted by SIGINT/SIGTERM/SIGHUP (a render writes its partial image first)\n";

// The command named by argv[1]; its exit code, or a thrown error.
int runCommand(int argc, char** argv) {
    if (argc < 2 || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "--help")) {
        std::fputs(kMainHelp, argc < 2 ? stderr : stdout);
        return argc < 2 ? 1 : 0;
    }
    const std::string cmd = argv[1];
    if (cmd == "devices") {
        printDevices(std::cout);  // no device: clrt::Error (exit 3) naming the cause
        return 0;
    }
    if (cmd == "render") return cmdRender(argc, argv);
    if (cmd == "tonemap") return cmdTonemap(argc, argv);
    if (cmd == "merge") return cmdMerge(argc, argv);
    throw Error("unknown command '" + cmd + "' (see clrt --help)", ExitCode::Usage);
}

}  // namespace

int main(int argc, char** argv) {
    installInterruptHandling();  // before any thread exists (MPI's included)
    int rc = 0;
    std::string who;  // "rank R: " in an MPI job of several ranks
    try {
        if (argc >= 2 && !std::strcmp(argv[1], "render")) {
            MpiJob& job = MpiJob::start(&argc, &argv);  // only when an MPI launcher started this process
            if (job.distributed()) who = "rank " + std::to_string(job.rank()) + " (" + job.host() + "): ";
        }
        rc = runCommand(argc, argv);
    } catch (const Error& e) {
        std::fprintf(stderr, "clrt: error: %s%s\n", who.c_str(), e.what());
        rc = int(e.code());
    } catch (const cl::Error& e) {
        std::fprintf(stderr, "clrt: error: %sOpenCL %s (%d)\n", who.c_str(), e.what(), e.err());
        rc = int(ExitCode::Device);
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "clrt: error: %sout of host memory\n", who.c_str());
        rc = int(ExitCode::Device);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "clrt: error: %s%s\n", who.c_str(), e.what());
        rc = 2;
    }
    std::fflush(stderr);
    MpiJob::get().end(rc);  // MPI_Finalize, or MPI_Abort after an error (ends the other ranks)
    return rc;
}
