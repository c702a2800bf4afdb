#pragma once
// `omega import SCENE.xml [-o SCENE.yaml] [-D name=value]...`: Mitsuba XML -> scene format v1.
// `omega import SCENE.gltf|.glb [-o SCENE.yaml] [--camera NAME]`: glTF 2.0 -> scene format v1.
#include <CLI/CLI.hpp>

#include <map>
#include <string>
#include <vector>

namespace omega {

struct ImportArgs {
    std::string scene;
    std::string output;
    std::vector<std::string> defines;  // name=value
    std::string camera;                // glTF: the camera to use
};

void add_import_command(CLI::App& app, ImportArgs& args);
int run_import(const ImportArgs& args);

// "name=value" strings -> map; a malformed one is reported on stderr and returns false.
bool parse_defines(const std::vector<std::string>& in, std::map<std::string, std::string>& out);

}  // namespace omega
