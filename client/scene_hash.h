#pragma once
// The identity a partial render carries (omega.scene_hash), so that `omega merge` refuses parts
// of different scenes, even when they sit at different paths on different machines.
#include <string>
#include <vector>

#include "scene/scene_desc.h"

namespace omega::client {

// Lowercase hex SHA-256 over the scene file's bytes, every file the description names (each by
// the name the scene writes and its own SHA-256, in name order) and the -D definitions (sorted).
// Files a mesh names inside itself (an OBJ's mtllib) are not included: Omega's materials come
// from the scene. Throws ClientError (exit 2) for an unreadable file.
std::string scene_content_hash(const std::string& scene_path, const SceneDesc& desc,
                               const std::vector<std::string>& defines);

}  // namespace omega::client
