#pragma once
// Texture fixtures written at run time through OpenImageIO, so no binary image is committed.
#include <cstdint>
#include <string>
#include <vector>

namespace omega::test {

// An 8-bit image (PNG, PPM, ... by the extension), rows top first, `channels` values per texel.
void write_image_u8(const std::string& path, int w, int h, int channels, const std::vector<uint8_t>& data);
// A float image (EXR, HDR), rows top first.
void write_image_f32(const std::string& path, int w, int h, int channels, const std::vector<float>& data);

// The closed form of the sRGB decoding (IEC 61966-2-1) of the 8-bit code c, in double.
double srgb8_to_linear(int c);

}  // namespace omega::test
