#include "scene/scene_files.h"

#include <fmt/format.h>

#include "io/file_gate.h"

namespace omega {

void for_each_scene_file(const SceneDesc& desc, const std::function<void(const SceneFileRef&)>& fn) {
    for (const ShapeDesc& s : desc.shapes)
        if (s.type == ShapeType::Mesh && !s.file.empty()) fn({s.file, s.written, s.file_loc.file.empty() ? s.loc : s.file_loc, "mesh"});
    for (const auto& [name, m] : desc.materials)
        for (const auto* t : m.texture_slots())
            if (*t && !(*t)->checker && !(*t)->embedded)  // a checkerboard or an embedded image reads no file
                fn({(*t)->file, (*t)->written, (*t)->file_loc.file.empty() ? (*t)->loc : (*t)->file_loc, "texture"});
    for (const LightDesc& l : desc.lights)
        if (l.type == LightType::EnvMap) fn({l.file, l.written, l.file_loc.file.empty() ? l.loc : l.file_loc, "envmap"});
}

const FileGate& scene_gate(const SceneDesc& desc) { return desc.files ? *desc.files : *FileGate::unconfined(); }

std::string SceneFileRef::prefix() const {
    return loc.key.empty() ? fmt::format("{}:{}: ", loc.file, loc.line) : fmt::format("{}:{}: {}: ", loc.file, loc.line, loc.key);
}

void check_scene_files(const SceneDesc& desc) {
    const FileGate& gate = scene_gate(desc);
    for_each_scene_file(desc, [&](const SceneFileRef& r) {
        try {
            gate.check(r.file, r.written);
        } catch (const FileRefused& e) {
            throw SceneError(r.prefix() + e.what());
        }
    });
}

}  // namespace omega
