#pragma once
// Bad input in a scene. The message is always "file:line: key: what is wrong".
// Library code throws this; only executables turn it into exit code 2.
#include <stdexcept>
#include <string>

namespace omega {

struct SceneError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

}  // namespace omega
