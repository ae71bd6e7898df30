// tonemap_cmd.h — `clrt tonemap IN.exr [-o OUT.png] [options]`: its command-line parser and driver
// (tone mapping itself is output/tonemap_device.h).
#pragma once

namespace clrt {

// argv[1] is "tonemap". Returns the exit code; throws clrt::Error on bad input or a failure.
// Refused before any image is read: an output that is not a plain .png/.exr file name, two outputs
// with one name, an output that is the input image or a file the --scene reads, an output directory
// that cannot be written.
int cmdTonemap(int argc, char** argv);
extern const char* const kTonemapHelp;

}  // namespace clrt
