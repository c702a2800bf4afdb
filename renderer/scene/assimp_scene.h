#pragma once
// An Assimp import through the scene's FileGate, for loaders that need more of a file than its
// triangles (the glTF importer reads its cameras, lights, materials and node graph this way).
#include <functional>
#include <string>

#include "scene/triangle_mesh.h"

struct aiScene;

namespace omega {

// Imports `path` with Assimp (post-processing steps `post_process`, aiProcess_* flags), every
// file it opens read through `gate` exactly as load_mesh_file reads them (a confined gate's
// refusal of any refuses the file), and calls `use` with the scene while it is alive. Imports
// are serialised process-wide (Assimp 5.2 has global state). Throws SceneError naming `loc`.
void read_assimp_scene(const FileGate& gate, const std::string& path, const SourceLoc& loc, const MeshFileOptions& opt,
                       unsigned post_process, const std::function<void(const aiScene&)>& use);

}  // namespace omega
