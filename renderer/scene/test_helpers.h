#pragma once
// Shared by the scene tests: temp folders and "this throws exactly that SceneError".
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <string>

#include "scene/scene_desc.h"
#include "scene/scene_error.h"
#include "shared_data.h"

namespace omega::test {

inline std::filesystem::path source_root() { return source_dir(); }

// A fresh folder under the system temp dir, removed at the end of the test.
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        std::random_device rd;
        path = std::filesystem::temp_directory_path() / ("omega_scene_test_" + std::to_string(rd()) + std::to_string(rd()));
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    std::filesystem::path write(const std::string& name, const std::string& text) const {
        auto p = path / name;
        std::filesystem::create_directories(p.parent_path());
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
};

template <class F>
std::string scene_error_of(F&& f) {
    try {
        f();
    } catch (const SceneError& e) {
        return e.what();
    }
    return "(no SceneError)";
}

// Whether some warning of `d` contains `part`; all of them, one a line, for failure messages.
inline bool has_warning(const SceneDesc& d, const std::string& part) {
    for (const auto& w : d.warnings)
        if (w.find(part) != std::string::npos) return true;
    return false;
}
inline std::string all_warnings(const SceneDesc& d) {
    std::string s;
    for (const auto& w : d.warnings) s += w + "\n";
    return s;
}

}  // namespace omega::test
