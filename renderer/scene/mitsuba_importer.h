#pragma once
// Mitsuba 3 XML -> SceneDesc: the subset that Bitterli's "Rendering resources" scenes use.
// See docs/scene-format.md ("Importing Mitsuba XML") for what is supported and what warns.
//
// - Every value goes through the same section parsers as a YAML v1 file (scene_parser.h), so the
//   checks, defaults and messages are the same, and the result written back as YAML
//   (scene_writer.h) parses to an equal SceneDesc.
// - Anything the importer does not support (a plugin, a parameter, an approximation it had to
//   make) is named in SceneDesc::warnings as "file:line: element: what"; nothing is dropped
//   silently.
// - Bad input (malformed XML, an undefined $variable, a missing mesh file, a value out of range)
//   throws SceneError "file:line: key: what is wrong", the line taken from the XML.
#include <map>
#include <memory>
#include <string>

#include "scene/scene_desc.h"

namespace omega {

struct MitsubaOptions {
    // Like `mitsuba -D name=value`: overrides the scene's <default name=... value=...>.
    std::map<std::string, std::string> defines;
    // Every file the scene names (meshes, bitmaps, envmaps) is checked or read through this
    // gate; null: FileGate::unconfined(). The result carries it on to Scene::build.
    std::shared_ptr<const FileGate> files;
    // glTF scenes only (load_scene_file): the camera to render, by name; empty = the first.
    std::string camera;
};

SceneDesc import_mitsuba_file(const std::string& path, const MitsubaOptions& options = {});
// `virtual_path` names the text in messages; relative file names resolve against its folder.
SceneDesc import_mitsuba_string(const std::string& xml, const std::string& virtual_path,
                                const MitsubaOptions& options = {});

// True for a path ending in .xml (case-insensitive).
bool is_mitsuba_path(const std::string& path);
// A scene in any format: Mitsuba XML for .xml (with `options`), glTF for .gltf/.glb (with
// options.camera), YAML v1 otherwise (a define given for a non-XML scene, or a camera for a
// non-glTF one, is an error, since it would be silently ignored).
SceneDesc load_scene_file(const std::string& path, const MitsubaOptions& options = {});

}  // namespace omega
