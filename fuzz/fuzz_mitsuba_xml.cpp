// Fuzzes the Mitsuba XML importer. Bad input must be a SceneError, never a crash.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scene/mitsuba_importer.h"
#include "scene/scene_error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    omega::import_mitsuba_string(text, "/nonexistent-fuzz-dir/fuzz.xml");
  } catch (const omega::SceneError&) {
  }
  return 0;
}
