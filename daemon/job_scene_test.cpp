// What a job may read, and what its messages may say.
#include "daemon/job_scene.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "daemon/config.h"
#include "scene/scene_error.h"

namespace omega::daemon {
namespace {

namespace fs = std::filesystem;

TEST(JobScene, MessagesLoseStatePaths) {
  const std::string st = "/var/lib/omega";
  EXPECT_EQ(redact_state_paths("x.yaml:3: shapes[0].file: cannot load mesh '/var/lib/omega/staging/12-3/files/meshes/a.obj': bad", st),
            "x.yaml:3: shapes[0].file: cannot load mesh 'meshes/a.obj': bad");
  EXPECT_EQ(redact_state_paths("read /var/lib/omega/jobs/7/files/t.png failed", st), "read t.png failed");
  EXPECT_EQ(redact_state_paths("'/var/lib/omega/jobs/7/result.exr' is not", st), "'<state>' is not");
  EXPECT_EQ(redact_state_paths("sqlite: /var/lib/omega/jobs.sqlite: locked, /var/lib/omega", st), "sqlite: <state>: locked, <state>");
  EXPECT_EQ(redact_state_paths("/var/lib/omegaX/file", st), "<state>");  // a sibling that merely shares the prefix
  EXPECT_EQ(redact_state_paths("nothing here", st), "nothing here");
}

TEST(JobScene, ScenesReadOnlyTheirFilesAndAllowedRoots) {
  const fs::path dir = fs::temp_directory_path() / ("omega_job_scene_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  JobPaths jp{(dir / "state/jobs/5").string()};
  fs::create_directories(jp.files());
  fs::create_directories(dir / "state/jobs/4");
  std::ofstream(dir / "state/jobs/4/result.exr") << "another job's image";
  std::ofstream(jp.files() + "/m.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
  auto scene = [&](const std::string& file) {
    std::ofstream(jp.scene()) << "omega: 1\nmaterials:\n  m: {type: diffuse}\nshapes:\n  - {type: mesh, material: m, file: '" + file + "'}\n";
  };
  scene("m.obj");
  EXPECT_NO_THROW(load_job_scene(jp, "j", "", "", {}));
  for (const std::string& bad : std::vector<std::string>{"../../4/result.exr", (dir / "state/jobs/4/result.exr").string(), "/etc/hostname"}) {
    scene(bad);
    try {
      load_job_scene(jp, "j", "", "", {});
      ADD_FAILURE() << bad;
    } catch (const SceneError& e) {
      EXPECT_EQ(std::string(e.what()), "j.yaml:5: shapes[0].file: '" + bad + "' is not a submitted asset or a regular file under an allowed root");
    }
  }
  fs::remove_all(dir);
}

TEST(JobScene, AllowedRootsMayNotOverlapTheStateDir) {
  Config c;
  c.state_dir = "/var/lib/omega";
  c.allowed_roots = {"/srv/assets"};
  EXPECT_NO_THROW(validate_config(c));
  for (const char* bad : {"/", "/var", "/var/lib/omega", "/var/lib/omega/jobs", "/var/lib/omega/../omega/"}) {
    c.allowed_roots = {bad};
    EXPECT_THROW(validate_config(c), std::runtime_error) << bad;
  }
  c.allowed_roots = {"/var/lib/omega-assets"};  // shares a prefix, not a folder
  EXPECT_NO_THROW(validate_config(c));
}

}  // namespace
}  // namespace omega::daemon
