#include "scene_hash.h"

#include <algorithm>
#include <map>

#include "asset_scan.h"
#include "client_error.h"
#include "io/file_gate.h"
#include "scene/scene_files.h"

namespace omega::client {

std::string scene_content_hash(const std::string& scene_path, const SceneDesc& desc,
                               const std::vector<std::string>& defines) {
    // Name -> hash; a map keeps the order independent of where the scene lists its files.
    std::map<std::string, std::string> files;
    for_each_scene_file(desc, [&](const SceneFileRef& f) {
        const std::string& name = f.written.empty() ? f.file : f.written;
        // Through the scene's gate, as the loaders read it (unconfined for a local render).
        if (!files.count(name)) {
            try {
                files[name] = sha256_bytes(scene_gate(desc).read(f.file, FileGate::kDefaultMaxBytes, f.written));
            } catch (const std::exception& e) {
                throw ClientError(kExitBadInput, f.prefix() + e.what());
            }
        }
    });
    std::string text = "omega-scene-v1\nscene " + sha256_file(scene_path) + "\n";
    for (const auto& [name, hash] : files) text += "file " + hash + " " + name + "\n";
    std::vector<std::string> sorted = defines;
    std::sort(sorted.begin(), sorted.end());
    for (const std::string& d : sorted) text += "define " + d + "\n";
    return sha256_bytes(text);
}

}  // namespace omega::client
