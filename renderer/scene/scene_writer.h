#pragma once
// SceneDesc -> scene format v1 (YAML). What `omega import` writes.
//
// Parsing the text again gives an equal SceneDesc (every field the parser reads, bit for bit;
// only source locations and warnings differ): numbers are written in their shortest form that
// reads back to the same float or double. The scene's warnings are written as comments at the top.
//
// An embedded image (BitmapDesc::embedded: a .glb's) has no file for a YAML to name, so it is
// named as the file it becomes: "<embedded_dir>/<EmbeddedImage::name>", relative to the YAML's
// folder. write_scene_file writes those files; `omega submit` sends their bytes from memory.
#include <memory>
#include <string>
#include <vector>

#include "scene/scene_desc.h"

namespace omega {

// Where write_scene_file puts the embedded images of the YAML `yaml_path`: the folder
// "<its stem>_textures" beside it (out.yaml -> out_textures), which belongs to that YAML.
std::string embedded_image_dir(const std::string& yaml_path);

// The scene's embedded images (each once, in the order the writer meets them) and the path,
// relative to the YAML's folder, that write_scene_yaml names each by. Two different images of
// one name (only a hand-made description can have them) get "_2", "_3", ... before the extension.
struct EmbeddedFile {
    std::string rel;  // "<embedded_dir>/<name>", '/'-separated
    std::shared_ptr<const EmbeddedImage> image;
};
std::vector<EmbeddedFile> embedded_files(const SceneDesc& desc, const std::string& embedded_dir);

// Mesh paths are written relative to `base_dir` when it is given (the folder the YAML file will
// live in), absolute otherwise; embedded images as embedded_files(desc, embedded_dir) names them.
std::string write_scene_yaml(const SceneDesc& desc, const std::string& base_dir = "", const std::string& embedded_dir = "");

// Writes the YAML to `path` (mesh paths relative to its folder), and each embedded image into
// embedded_image_dir(path), replacing a file of the same name there (as the YAML itself is
// replaced; each is written whole to a temporary name first, then renamed). Files of other
// names in that folder are left alone. Throws std::runtime_error naming the path on I/O failure.
void write_scene_file(const SceneDesc& desc, const std::string& path);

}  // namespace omega
