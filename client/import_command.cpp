#include "import_command.h"

#include <fmt/format.h>

#include <filesystem>

#include "scene/gltf_importer.h"
#include "scene/mitsuba_importer.h"
#include "scene/scene_error.h"
#include "scene/scene_writer.h"

namespace omega {

bool parse_defines(const std::vector<std::string>& in, std::map<std::string, std::string>& out) {
    for (const std::string& d : in) {
        size_t eq = d.find('=');
        if (eq == std::string::npos || eq == 0) {
            fmt::print(stderr, "omega: -D {}: expected name=value\n", d);
            return false;
        }
        out[d.substr(0, eq)] = d.substr(eq + 1);
    }
    return true;
}

void add_import_command(CLI::App& app, ImportArgs& a) {
    auto* cmd = app.add_subcommand("import", "Convert a Mitsuba 3 XML or glTF 2.0 scene to Omega's YAML scene format");
    cmd->add_option("scene", a.scene, "Mitsuba XML scene (*.xml) or glTF 2.0 scene (*.gltf, *.glb)")->required();
    cmd->add_option("-o,--output", a.output, "Output YAML (default: the scene's name with .yaml)");
    cmd->add_option("-D,--define", a.defines, "Mitsuba XML: set a scene <default> variable, name=value (repeatable)");
    cmd->add_option("--camera", a.camera, "glTF: the camera to use (node or camera name; default: the first)");
}

int run_import(const ImportArgs& a) {
    MitsubaOptions opt;
    if (!parse_defines(a.defines, opt.defines)) return 2;
    opt.camera = a.camera;
    SceneDesc desc;
    try {
        if (!is_mitsuba_path(a.scene) && !is_gltf_path(a.scene))
            throw SceneError(a.scene + ": omega import reads Mitsuba XML (*.xml) and glTF (*.gltf, *.glb) scenes");
        desc = load_scene_file(a.scene, opt);
    } catch (const SceneError& e) {
        fmt::print(stderr, "omega: {}\n", e.what());
        return 2;
    }
    for (const auto& w : desc.warnings) fmt::print(stderr, "omega: warning: {}\n", w);
    std::string out = a.output.empty() ? std::filesystem::path(a.scene).stem().string() + ".yaml" : a.output;
    try {
        write_scene_file(desc, out);
    } catch (const std::exception& e) {
        fmt::print(stderr, "omega: {}\n", e.what());
        return 1;
    }
    fmt::print("{}: {} shapes, {} materials, {} lights, {} warnings\n", out, desc.shapes.size(), desc.materials.size(),
               desc.lights.size(), desc.warnings.size());
    return 0;
}

}  // namespace omega
