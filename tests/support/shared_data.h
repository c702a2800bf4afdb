#pragma once
// The shared data set (Bitterli's scenes with their reference renders) lies beside the checkout
// as ../shared, on a developer's machine and in CI alike; it is found relative to the source
// tree, never by an absolute path.
#include <string>

namespace omega::test {

// The source tree (OMEGA_SOURCE_DIR, absolute): not __FILE__, which a compiler launcher such as
// ccache with base_dir may make relative to the build directory.
std::string source_dir();

// OMEGA_SOURCE_DIR/../shared/<rel>.
std::string shared_path(const std::string& rel);

// Whether `path` exists. Where it does not: under CI (the CI environment variable is set) the
// current test fails, since a missing file there would silently skip what CI must check;
// elsewhere the caller skips. Use: if (!test::shared_available(p)) GTEST_SKIP() << p;
bool shared_available(const std::string& path);

}  // namespace omega::test
