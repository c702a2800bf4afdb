#pragma once
// SceneDesc -> scene format v1 (YAML). What `omega import` writes.
//
// Parsing the text again gives an equal SceneDesc (every field the parser reads, bit for bit;
// only source locations and warnings differ): numbers are written in their shortest form that
// reads back to the same float or double. The scene's warnings are written as comments at the top.
#include <string>

#include "scene/scene_desc.h"

namespace omega {

// Mesh paths are written relative to `base_dir` when it is given (the folder the YAML file will
// live in), absolute otherwise.
std::string write_scene_yaml(const SceneDesc& desc, const std::string& base_dir = "");

// Writes the YAML to `path` (mesh paths relative to its folder). Throws std::runtime_error naming
// the path on I/O failure.
void write_scene_file(const SceneDesc& desc, const std::string& path);

}  // namespace omega
