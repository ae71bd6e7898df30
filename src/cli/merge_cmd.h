// merge_cmd.h — `clrt merge PARTS... -o OUTDIR`: the parts of a job array (clrt render --part K/N) put
// together into the camera's usual outputs (src/dist/part_file.h).
#pragma once

namespace clrt {

// Runs `clrt merge` (argv[1] == "merge"); returns the exit code or throws clrt::Error.
int cmdMerge(int argc, char** argv);

}  // namespace clrt
