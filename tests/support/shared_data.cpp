#include "shared_data.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

namespace omega::test {

std::string source_dir() { return OMEGA_SOURCE_DIR; }

std::string shared_path(const std::string& rel) {
    return (std::filesystem::path(OMEGA_SOURCE_DIR) / ".." / "shared" / rel).lexically_normal().string();
}

bool shared_available(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::exists(path, ec)) return true;
    const char* ci = std::getenv("CI");
    if (ci && *ci) ADD_FAILURE() << path << " is missing: CI must have ../shared beside the checkout";
    return false;
}

}  // namespace omega::test
