#pragma once
// Bad input in a scene. The message is always "file:line: key: what is wrong".
// Library code throws this; only executables turn it into exit code 2.
#include <stdexcept>
#include <string>

namespace omega {

struct SceneError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

// Scene::build stopped because its caller asked (a cancelled or shut-down job); not an error
// of the scene.
struct BuildCancelled : std::runtime_error {
    BuildCancelled() : std::runtime_error("the scene build was cancelled") {}
};

}  // namespace omega
