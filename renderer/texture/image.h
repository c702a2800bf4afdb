#pragma once
// Decoded texture images: linear RGB floats, as the renderer looks them up.
#include <memory>
#include <string>
#include <vector>

#include "math/vec.h"

namespace omega {

struct Image {
    int width = 0, height = 0;
    std::vector<Rgb> texels;  // row-major; row 0 is the first row stored in the file (its top)
    const Rgb& at(int x, int y) const { return texels[size_t(y) * size_t(width) + size_t(x)]; }
};

// The sRGB transfer function, inverted (IEC 61966-2-1), as Mitsuba decodes 8-bit textures.
float srgb_to_linear(float encoded);

// Loads `path` through OpenImageIO. Integer pixel data (8- and 16-bit PNG, JPEG, ...) is
// sRGB-encoded and decoded to linear unless `raw`; float data (EXR, HDR) is linear as stored.
// One channel is grey; a second or fourth (alpha) channel is ignored. Because every image is a
// reflectance, values are clamped to [0, 1]; a NaN, an infinity or a negative value is an error.
// Throws SceneError "<where>cannot read texture '<path>': <why>" on any failure.
std::shared_ptr<const Image> load_image(const std::string& path, bool raw, const std::string& where);

}  // namespace omega
