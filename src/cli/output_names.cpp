// output_names.cpp — output name, collision and input-identity checks (see output_names.h).
#include "cli/output_names.h"

#include <cctype>
#include <cstdio>
#include <filesystem>
#include <map>

#include "image/image.h"
#include "output/output.h"
#include "util/error.h"

namespace clrt {
namespace fs = std::filesystem;

void checkOutputDirectory(const std::string& dir) {
    std::error_code ec;
    if (!fs::exists(dir, ec)) throw Error(dir + ": output directory does not exist", ExitCode::Output);
    if (!fs::is_directory(dir, ec)) throw Error(dir + ": output directory is not a directory", ExitCode::Output);
    try {
        discardTemporary(createTemporary((fs::path(dir) / "clrt-write-check").string()));
    } catch (const Error& e) {
        std::string why = e.what();
        const size_t colon = why.rfind(": ");
        throw Error(dir + ": output directory is not writable" + (colon == std::string::npos ? "" : why.substr(colon)),
                    ExitCode::Output);
    }
}

namespace {

std::string quoted(const std::string& s) {
    std::string q = "'";
    for (unsigned char c : s) {
        if (c < 0x20 || c == 0x7f) {
            char buf[8];
            std::snprintf(buf, sizeof buf, "\\x%02x", c);
            q += buf;
        } else {
            q += char(c);
        }
    }
    return q + "'";
}

std::string folded(const std::string& s) {
    std::string f = s;
    for (char& c : f) c = char(std::tolower(static_cast<unsigned char>(c)));
    return f;
}

}  // namespace

std::vector<PlannedOutput> planRenderOutputs(const Scene& scene, const std::vector<const Camera*>& cams,
                                             const std::string& outDir) {
    std::vector<PlannedOutput> out;
    std::map<std::string, std::string> owner;  // folded name -> who writes it
    auto add = [&](const Camera& cam, const std::string& name, const std::string& what) {
        const std::string who = "camera " + std::to_string(cam.id) + ": " + what;
        const std::string problem = plainNameProblem(name);
        if (!problem.empty())
            throw Error(scene.path + ": " + who + " " + quoted(name) + " is not a plain file name (" + problem + ")");
        auto ins = owner.emplace(folded(name), who);
        if (!ins.second)
            throw Error(scene.path + ": " + who + " " + quoted(name) + " names the same output file as " + ins.first->second);
        out.push_back({(fs::path(outDir) / name).string(), who + " " + quoted(name)});
    };
    for (const Camera* cam : cams) {
        const std::string ext = lowerExtension(cam->imageName);
        add(*cam, cam->imageName, "ImageName");
        if (ext != ".png" && ext != ".exr")
            throw Error(scene.path + ": camera " + std::to_string(cam->id) + ": ImageName " + quoted(cam->imageName) +
                        " must end in .png or .exr");
        if (ext == ".exr")
            for (const std::string& png : tonemapPngPaths(cam->imageName, cam->tonemaps))
                add(*cam, png, "tone-mapped PNG (Tonemap Extension)");
    }
    return out;
}

std::vector<std::string> sceneInputs(const Scene& scene) {
    std::vector<std::string> in = {scene.path};
    in.insert(in.end(), scene.plyPaths.begin(), scene.plyPaths.end());
    in.insert(in.end(), scene.imagePaths.begin(), scene.imagePaths.end());
    return in;
}

void checkOutputsAreNotInputs(const std::vector<PlannedOutput>& outputs, const std::vector<std::string>& inputs,
                              const std::string& who) {
    for (const PlannedOutput& o : outputs) {
        std::error_code ec;
        if (!fs::exists(o.path, ec)) continue;  // a dangling symlink is replaced, never followed
        if (fs::is_directory(fs::symlink_status(o.path, ec)))
            throw Error(o.path + ": cannot write output file: a directory has its name", ExitCode::Output);
        for (const std::string& in : inputs)
            if (fs::equivalent(o.path, in, ec))
                throw Error(who + ": " + o.what + ": writing " + o.path + " would overwrite the input file " + in);
    }
}

}  // namespace clrt
