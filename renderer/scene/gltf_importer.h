#pragma once
// glTF 2.0 (.gltf, .glb) -> SceneDesc. See docs/scene-format.md ("Importing glTF") for what maps
// to what, the photometric units and every approximation.
//
// - Assimp (already Omega's mesh loader) reads the file: node graph, cameras, KHR_lights_punctual
//   lights and metallic-roughness materials, every file it opens read through the scene's
//   FileGate. The few things Assimp 5.2 drops (extensionsUsed, KHR_materials_emissive_strength,
//   the buffer and image uris before they are opened) are read from the glTF's own JSON through
//   yaml-cpp, a JSON superset reader Omega already uses.
// - The geometry stays in the glTF file: each material becomes one `mesh` shape naming the file
//   and the Assimp meshes drawn with that material (`meshes: [...]`), placed by the file's nodes.
//   So `omega import` writes a small YAML beside which the .gltf/.bin stay the assets, and the
//   daemon path (submit with assets) carries them like any mesh file.
// - Every approximation is warned once per kind, naming the file and the glTF objects; a buffer
//   or image uri the gate refuses is an error naming the file and the key (`buffers[0].uri`).
#include <memory>
#include <string>

#include "scene/scene_desc.h"

namespace omega {

struct GltfOptions {
    // The camera to render: a camera node's name or a glTF camera's name. Empty: the first camera.
    std::string camera;
    // Every file the scene names is checked or read through this gate; null: unconfined.
    std::shared_ptr<const FileGate> files;
};

SceneDesc import_gltf_file(const std::string& path, const GltfOptions& options = {});

// True for a path ending in .gltf or .glb (case-insensitive).
bool is_gltf_path(const std::string& path);

// Luminous efficacy used to turn glTF's photometric light units into Omega's radiometric ones
// (lm/W): the KHR_lights_punctual spec's candela and lux over 683, the same constant Blender's
// exporter multiplies watts by, so that a Blender light comes back with its own W/(4 pi sr).
inline constexpr double kGltfLumensPerWatt = 683.0;

}  // namespace omega
