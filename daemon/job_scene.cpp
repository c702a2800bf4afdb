#include "daemon/job_scene.h"

#include <cctype>
#include <cstring>
#include <filesystem>

#include "daemon/checkpoint.h"
#include "io/file_gate.h"
#include "scene/scene_error.h"
#include "scene/scene_parser.h"

namespace omega::daemon {

namespace fs = std::filesystem;

namespace {

std::string strip_all(std::string s, const std::string& prefix) {
  for (std::size_t pos; (pos = s.find(prefix)) != std::string::npos;) s.erase(pos, prefix.size());
  return s;
}

bool path_char(char c) { return !(std::isspace(static_cast<unsigned char>(c)) || c == '\'' || c == '"' || c == ':' || c == ','); }

std::string redact_one(const std::string& msg, const std::string& state) {
  if (state.empty() || state == "/") return msg;
  std::string out;
  std::size_t from = 0;
  for (std::size_t pos; (pos = msg.find(state, from)) != std::string::npos;) {
    std::size_t end = pos + state.size();
    while (end < msg.size() && path_char(msg[end])) ++end;
    out.append(msg, from, pos - from);
    // STATE/{jobs,staging}/X/files/REST -> REST
    std::string rest = msg.substr(pos + state.size(), end - pos - state.size());
    std::string shown = "<state>";
    for (const char* kind : {"/jobs/", "/staging/"}) {
      if (rest.rfind(kind, 0) != 0) continue;
      std::size_t slash = rest.find('/', std::strlen(kind));
      if (slash != std::string::npos && rest.compare(slash, 7, "/files/") == 0) shown = rest.substr(slash + 7);
    }
    out += shown;
    from = end;
  }
  out.append(msg, from, std::string::npos);
  return out;
}

}  // namespace

std::string redact_state_paths(const std::string& msg, const std::string& state_dir) {
  std::error_code ec;
  std::string canon = fs::weakly_canonical(fs::absolute(state_dir, ec), ec).string();
  std::string plain = fs::absolute(state_dir, ec).lexically_normal().string();
  for (std::string* s : {&canon, &plain})
    while (s->size() > 1 && s->back() == '/') s->pop_back();
  // The longer first, so that one is not left half-replaced by the other.
  if (canon.size() < plain.size()) std::swap(canon, plain);
  return redact_one(redact_one(msg, canon), plain);
}

std::string scene_file_name(const std::string& job_name) {
  bool ok = !job_name.empty() && job_name.size() <= 200 && job_name[0] != '.';
  for (char c : job_name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.')) ok = false;
  return (ok ? job_name : std::string("scene")) + ".yaml";
}

std::shared_ptr<const FileGate> job_gate(const JobPaths& p, const std::vector<std::string>& allowed_roots) {
  std::vector<std::string> roots{p.files()};
  roots.insert(roots.end(), allowed_roots.begin(), allowed_roots.end());
  return FileGate::confined(std::move(roots));
}

SceneDesc load_job_scene(const JobPaths& p, const std::string& job_name, const std::string& integrator,
                         const std::string& sampler, const std::vector<std::string>& allowed_roots) {
  const std::string files = p.files();
  const std::string virt = files + "/" + scene_file_name(job_name);
  std::string yaml = read_file(p.scene());
  SceneDesc desc;
  try {
    desc = parse_scene_string(yaml, virt, job_gate(p, allowed_roots));
  } catch (const SceneError& e) {
    throw SceneError(strip_all(e.what(), files + "/"));
  }
  const std::string shown = scene_file_name(job_name);
  if (integrator == "path") desc.integrator.type = IntegratorType::Path;
  if (integrator == "light") desc.integrator.type = IntegratorType::Light;
  if (integrator == "bdpt") desc.integrator.type = IntegratorType::Bdpt;
  if (!integrator.empty() && integrator != "path" && integrator != "light" && integrator != "bdpt")
    throw SceneError(shown + ":1: integrator: unknown integrator '" + integrator + "'");
  if (auto s = sampler_from_name(sampler)) desc.integrator.sampler = *s;
  else if (!sampler.empty()) throw SceneError(shown + ":1: sampler: unknown sampler '" + sampler + "' (sobol, independent)");
  return desc;
}

}  // namespace omega::daemon
