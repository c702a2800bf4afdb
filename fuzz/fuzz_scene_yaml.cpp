// Fuzzes the YAML scene parser (scene format v1). Bad input must be a SceneError naming the
// file and line, never a crash or another exception type.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scene/scene_error.h"
#include "scene/scene_parser.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    omega::parse_scene_string(text, "/nonexistent-fuzz-dir/fuzz.yaml");
  } catch (const omega::SceneError&) {
  }
  return 0;
}
