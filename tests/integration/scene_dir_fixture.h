#pragma once
// A gtest fixture for command-line tests: a fresh temporary folder per test (named for the test
// and the process), holding scene.yaml with the scene text the test suite gives; removed after.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace omega::test {

// A diffuse sphere in front of a mirror, lit by a point light: direct, indirect and mirror paths
// (the light path expression and breakdown CLI tests), with the AOV `direct`.
inline const char* kMirrorSphereScene = R"(omega: 1
integrator: {type: path, max_depth: 4}
sensor:
  type: perspective
  fov: 50
  to_world: {look_at: {origin: [0, 0, -3], target: [0, 0, 0], up: [0, 1, 0]}}
  film: {width: 16, height: 12, aov: {direct: "L D E"}}
materials:
  white: {type: diffuse, reflectance: [0.5, 0.5, 0.5]}
  mirror: {type: conductor}
shapes:
  - {type: sphere, center: [0, 0, 0], radius: 0.7, material: white}
  - {type: rectangle, to_world: [{scale: 3}, {translate: [0, 0, 1.5]}], material: mirror}
lights:
  - {type: point, position: [0, 2, -2], intensity: [5, 5, 5]}
)";

class SceneDirTest : public ::testing::Test {
protected:
    SceneDirTest(std::string prefix, std::string scene_text) : prefix_(std::move(prefix)), text_(std::move(scene_text)) {}
    void SetUp() override {
        dir_ = std::filesystem::temp_directory_path() /
               std::filesystem::path(prefix_ + std::to_string(::getpid()) + "_" +
                                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
        std::filesystem::create_directories(dir_);
        scene_ = (dir_ / "scene.yaml").string();
        std::ofstream(scene_) << text_;
    }
    void TearDown() override { std::filesystem::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    std::string prefix_, text_;
    std::filesystem::path dir_;
    std::string scene_;
};

}  // namespace omega::test
