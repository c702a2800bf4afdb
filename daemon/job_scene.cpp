#include "daemon/job_scene.h"

#include <cctype>
#include <filesystem>

#include "daemon/checkpoint.h"
#include "scene/scene_error.h"
#include "scene/scene_parser.h"

namespace omega::daemon {

namespace fs = std::filesystem;

namespace {

bool inside(const fs::path& file, const fs::path& root) {
  std::error_code ec;
  fs::path f = fs::weakly_canonical(file, ec);
  if (ec) return false;
  fs::path r = fs::weakly_canonical(root, ec);
  if (ec) return false;
  auto fi = f.begin();
  for (auto ri = r.begin(); ri != r.end(); ++ri, ++fi) {
    if (ri->empty()) continue;  // trailing slash
    if (fi == f.end() || *fi != *ri) return false;
  }
  return true;
}

std::string strip_all(std::string s, const std::string& prefix) {
  for (std::size_t pos; (pos = s.find(prefix)) != std::string::npos;) s.erase(pos, prefix.size());
  return s;
}

}  // namespace

std::string scene_file_name(const std::string& job_name) {
  bool ok = !job_name.empty() && job_name.size() <= 200 && job_name[0] != '.';
  for (char c : job_name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) ok = false;
  return (ok ? job_name : std::string("scene")) + ".yaml";
}

SceneDesc load_job_scene(const JobPaths& p, const std::string& job_name, const std::string& integrator,
                         const std::vector<std::string>& allowed_roots) {
  const std::string files = p.files();
  const std::string virt = files + "/" + scene_file_name(job_name);
  std::string yaml = read_file(p.scene());
  SceneDesc desc;
  try {
    desc = parse_scene_string(yaml, virt);
  } catch (const SceneError& e) {
    throw SceneError(strip_all(e.what(), files + "/"));
  }
  const std::string shown = scene_file_name(job_name);
  for (const ShapeDesc& s : desc.shapes) {
    if (s.file.empty()) continue;
    bool ok = inside(s.file, files);
    for (const auto& root : allowed_roots) ok = ok || inside(s.file, root);
    if (!ok) {
      std::string where = s.loc.file.empty() ? shown : strip_all(s.loc.file, files + "/");
      throw SceneError(where + ":" + std::to_string(s.loc.line) + ": " + (s.loc.key.empty() ? "file" : s.loc.key) +
                       ".file: '" + strip_all(s.file, files + "/") +
                       "' is neither a submitted asset nor under an allowed root");
    }
  }
  if (integrator == "path") desc.integrator.type = IntegratorType::Path;
  if (integrator == "light") desc.integrator.type = IntegratorType::Light;
  if (integrator == "bdpt") desc.integrator.type = IntegratorType::Bdpt;
  if (!integrator.empty() && integrator != "path" && integrator != "light" && integrator != "bdpt")
    throw SceneError(shown + ":1: integrator: unknown integrator '" + integrator + "'");
  return desc;
}

}  // namespace omega::daemon
