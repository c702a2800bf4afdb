#pragma once
// What `omega submit` sends: the scene YAML plus every file it references (meshes), each named
// as the scene names it and identified by SHA-256 (docs/protocol.md, "Submit exchange").
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "protocol/messages.h"

namespace omega::client {

struct ScannedAsset {
    std::string name;    // the path as the (possibly rewritten) scene writes it: relative, '/'-separated
    std::string path;    // where the bytes are on this machine
    std::string sha256;  // lowercase hex
    uint64_t size = 0;
    // Set for an image embedded in the scene file (a .glb's): these are the bytes, and `path`
    // only names it for messages ("scene.glb#blender_scene_textures/checker.png").
    std::shared_ptr<const std::string> data;
};

struct ScannedScene {
    std::string path;  // the scene file
    std::string name;  // its stem: names the job and default outputs
    std::string yaml;  // what travels as the submit payload
    std::vector<ScannedAsset> assets;  // unique by name
    std::vector<std::string> warnings;  // from the scene parser
    std::vector<protocol::AssetRef> refs() const;
};

// Parses the scene with the renderer's parser (so a bad scene is reported here, with
// file:line, before anything is sent) and hashes every file it references: meshes (and the
// files they name), bitmap textures of any material parameter, an envmap's image. A Mitsuba XML
// or glTF scene is imported first and travels as the YAML `omega import` would write beside it; the
// images a .glb embeds travel as the files that import would write, "<scene stem>_textures/<name>",
// their bytes taken from memory (ScannedAsset::data), never from a file of that name. A file named by a
// clean relative path (`meshes/bunny.obj`) keeps its name and the YAML travels unchanged; one
// named by an absolute path or one that climbs out with `..` is renamed
// `assets/<first 16 hex of its sha256>/<file name>` and the scene's `file:` value rewritten to
// match. Throws ClientError (exit 2) for a bad scene or an unreadable file.
ScannedScene scan_scene(const std::string& scene_path);

// Lowercase hex SHA-256 of a file's bytes (OpenSSL EVP); throws ClientError (exit 2).
std::string sha256_file(const std::string& path, uint64_t* size = nullptr);
std::string sha256_bytes(const std::string& bytes);

}  // namespace omega::client
