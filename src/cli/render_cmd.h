// render_cmd.h — `clrt render SCENE [options]`: loads the scene, checks the outputs and the devices
// before any work, flattens it, builds one renderer per device, renders and writes every camera
// (cli/camera_drivers.h) and prints the stats (cli/render_stats.h). Options: cli/render_args.h.
#pragma once

namespace clrt {

// argv[1] is "render". Returns the exit code (128 + signal when interrupted); throws clrt::Error on
// bad input or a failure.
int cmdRender(int argc, char** argv);

}  // namespace clrt
