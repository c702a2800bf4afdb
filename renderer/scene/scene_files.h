#pragma once
// Every file a scene description names (mesh files, bitmap textures), with where it is named:
// one list for the gate check after parsing, for the loaders and for the client's asset scan.
#include <functional>
#include <string>

#include "scene/scene_desc.h"

namespace omega {

struct SceneFileRef {
    const std::string& file;     // absolute path
    const std::string& written;  // as the scene wrote it ("" when unknown)
    const SourceLoc& loc;        // of the file value (its key ends in ".file")
    const char* what;            // "mesh" or "texture"
    // "FILE:LINE: KEY: " for messages about this file.
    std::string prefix() const;
};

void for_each_scene_file(const SceneDesc& desc, const std::function<void(const SceneFileRef&)>& fn);

// The gate that governs `desc` (its own, or FileGate::unconfined()).
const FileGate& scene_gate(const SceneDesc& desc);

// Checks each file through the scene's gate without reading it. Throws SceneError
// "FILE:LINE: KEY: 'NAME' ..." for the first the gate refuses.
void check_scene_files(const SceneDesc& desc);

}  // namespace omega
