// Scene loading entry point. loadScene reads a CENG795 scene file, picks the XML or the JSON reader by
// content (first non-whitespace character '<' or '{', a UTF-8 BOM skipped), and walks it into the
// scene model (scene.h) with the one shared walker (scene_walker.h). Reads every element of the
// format; see shared/SCENE_FORMAT.md. Throws clrt::Error with "file:line:col: ..." (XML) or
// "file: Key.Path: ..." (JSON) on bad input.
#pragma once
#include <string>

#include "scene/scene.h"

namespace clrt {
Scene loadScene(const std::string& path);
}  // namespace clrt
