#pragma once
// Scene format v1 (YAML) -> SceneDesc. See docs/scene-format.md for every key.
// Throws SceneError "file:line: key: what is wrong" for any bad input; never loads meshes or
// textures, but checks every file they name through the FileGate (regular, readable, and beneath
// the gate's roots when confined), so that the error points at the scene line.
#include <memory>
#include <string>

#include "math/transform.h"
#include "scene/param_bag.h"
#include "scene/scene_desc.h"

namespace omega {

SceneDesc parse_scene_file(const std::string& path);
// `virtual_path` names the text in messages; relative file names resolve against its folder.
// `files` governs every file the scene names (null: unconfined); the result carries it.
SceneDesc parse_scene_string(const std::string& yaml, const std::string& virtual_path,
                             std::shared_ptr<const FileGate> files = nullptr);

// A `to_world` value: {matrix: [...]}, {look_at: {...}}, a single translate/rotate/scale mapping,
// or a list of those applied in order (the first to the points first). Checks that the result is
// finite, affine and invertible.
Mat4 parse_to_world(const ParamValue& v);

// The section parsers, for importers that build a YAML value per entity (e.g. the Mitsuba XML
// importer): the same keys, defaults and checks as in a v1 file, and the same error messages.
IntegratorDesc parse_integrator_value(const ParamValue& v);
SensorDesc parse_sensor_value(const ParamValue& v);  // includes film and halt keys
MaterialDesc parse_material_value(const ParamValue& v, const std::string& name, std::vector<std::string>& warnings);
EmitterDesc parse_emitter_value(const ParamValue& v);
LightDesc parse_light_value(const ParamValue& v);

}  // namespace omega
