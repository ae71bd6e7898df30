// output_names.h — the checks every run makes on its output files before any work starts: each name
// is a plain file name of the right image type, no two outputs of a run share a name, none of them
// is (by filesystem identity) a file the run reads, and the output directory really accepts a new
// file. Output names come from scenes (ImageName, Tonemap Extension) and the command line, so they
// are untrusted: nothing is ever written outside the output directory.
#pragma once
#include <string>
#include <vector>

#include "output/output.h"
#include "scene/scene.h"

namespace clrt {

// (plainNameProblem and lowerExtension, the name rules themselves, are in output/output.h.)

// The directory exists, is a directory, and a file can be created in it (a temporary is created and
// removed). Throws clrt::Error, ExitCode::Output, naming `dir`.
void checkOutputDirectory(const std::string& dir);

struct PlannedOutput {
    std::string path;  // outDir / name
    std::string what;  // for messages: "camera 1: ImageName 'x.exr'"
};

// Every file a render of `cams` writes into outDir (the ImageName, and for an .exr one tone-mapped
// .png per Tonemap block). Throws clrt::Error (ExitCode::BadInput) naming the scene file if a name is
// not plain, an ImageName is not .png/.exr, or two outputs share a name (compared case-insensitively).
std::vector<PlannedOutput> planRenderOutputs(const Scene& scene, const std::vector<const Camera*>& cams,
                                             const std::string& outDir);

// Every file `scene` reads: the scene file, its PLY files and images.
std::vector<std::string> sceneInputs(const Scene& scene);

// Throws clrt::Error (ExitCode::BadInput), naming `who` and the input, if an output is the same file
// as an input (std::filesystem::equivalent: through symlinks and hard links alike); ExitCode::Output
// if a directory has an output's name (the rename would fail after the whole render).
void checkOutputsAreNotInputs(const std::vector<PlannedOutput>& outputs, const std::vector<std::string>& inputs,
                              const std::string& who);

}  // namespace clrt
