#pragma once
// A job's files and its scene. Layout of STATE/jobs/ID/:
//   scene.yaml       the submitted scene text
//   files/NAME       the submitted assets (hard links into the asset cache)
//   checkpoint.bin   the film at the last checkpointed pass boundary
//   result.exr       the finished image
// The scene is parsed as if it were files/<name>.yaml, so relative paths resolve among the
// assets. Any thread (pure functions over the filesystem).
#include <memory>
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

// The FileGate of a job: its own files/ and the allowed roots, nothing else (never the state
// directory: config validation keeps allowed_roots apart from it).
std::shared_ptr<const FileGate> job_gate(const JobPaths& p, const std::vector<std::string>& allowed_roots);

// Parses the job's scene through job_gate() and applies the integrator and sampler overrides
// (empty: none).
// Every file the scene names must be a regular file inside files/ or under one of
// allowed_roots, else SceneError; the result carries the gate, so Scene::build reads through it
// too. Messages read "NAME.yaml:LINE: key: what" (the job directory is not shown).
SceneDesc load_job_scene(const JobPaths& p, const std::string& job_name, const std::string& integrator,
                         const std::string& sampler, const std::vector<std::string>& allowed_roots);

// `msg` as a client may see it: every absolute path into the state directory is cut down to
// what the scene named ("STATE/jobs/7/files/meshes/a.obj" -> "meshes/a.obj", likewise for
// staging) or, if it is not a job's file, to "<state>". Operators see the full path in the log.
std::string redact_state_paths(const std::string& msg, const std::string& state_dir);

}  // namespace omega::daemon
