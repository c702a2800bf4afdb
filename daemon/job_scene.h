#pragma once
// A job's files and its scene. Layout of STATE/jobs/ID/:
//   scene.yaml       the submitted scene text
//   files/NAME       the submitted assets (hard links into the asset cache)
//   checkpoint.bin   the film at the last checkpointed pass boundary
//   result.exr       the finished image
// The scene is parsed as if it were files/<name>.yaml, so relative paths resolve among the
// assets. Any thread (pure functions over the filesystem).
#include <string>
#include <vector>

#include "scene/scene_desc.h"

namespace omega::daemon {

struct JobPaths {
  std::string dir;
  std::string scene() const { return dir + "/scene.yaml"; }
  std::string files() const { return dir + "/files"; }
  std::string checkpoint() const { return dir + "/checkpoint.bin"; }
  std::string result() const { return dir + "/result.exr"; }
};

// "cornell" -> "cornell.yaml"; anything unsafe as a file name -> "scene.yaml".
std::string scene_file_name(const std::string& job_name);

// Parses the job's scene and applies the integrator override (empty: none). Every file the
// scene names must lie inside files/ or under one of allowed_roots, else SceneError. Messages
// read "NAME.yaml:LINE: key: what" (the job directory is not shown).
SceneDesc load_job_scene(const JobPaths& p, const std::string& job_name, const std::string& integrator,
                         const std::vector<std::string>& allowed_roots);

}  // namespace omega::daemon
