#pragma once
// Decoded texture images: linear RGB floats, as the renderer looks them up.
#include <memory>
#include <string>
#include <vector>

#include "math/vec.h"

namespace omega {

class FileGate;

struct Image {
    int width = 0, height = 0;
    std::vector<Rgb> texels;  // row-major; row 0 is the first row stored in the file (its top)
    const Rgb& at(int x, int y) const { return texels[size_t(y) * size_t(width) + size_t(x)]; }
};

// The sRGB transfer function, inverted (IEC 61966-2-1), as Mitsuba decodes 8-bit textures.
float srgb_to_linear(float encoded);

// An image file's pixels as stored, converted to float: `channels` values a texel, row-major,
// the top row first.
struct ImagePixels {
    int width = 0, height = 0, channels = 0;
    bool is_float = false;  // the file stores float data (EXR, HDR, PFM): linear, not sRGB
    std::vector<float> data;
};

// Reads `path` through `gate` into memory and decodes it there: OpenImageIO gets an in-memory
// proxy and never a path of its own, so no image reader can open anything the gate did not
// admit. The format comes from the file's magic bytes, else its extension. At most 2^26
// texels (8192 x 8192), checked before any pixel is decoded. Messages name the file as
// `written` (or the gate shows it). Throws SceneError "<where>cannot read <what> '<name>': <why>".
ImagePixels decode_image(const FileGate& gate, const std::string& path, const std::string& written,
                         const std::string& where, const std::string& what = "image");

// The same for bytes already in memory (an image embedded in a .glb): `path` only lends its
// extension when the magic bytes name no format; `name` is what messages show. The same bound
// on texels applies, checked before any pixel is decoded.
ImagePixels decode_image_bytes(const std::string& bytes, const std::string& path, const std::string& name,
                               const std::string& where, const std::string& what = "image");

// Loads a texture. Integer pixel data (8- and 16-bit PNG, JPEG, ...) is
// sRGB-encoded and decoded to linear unless `raw`; float data (EXR, HDR) is linear as stored.
// One channel is grey; a second or fourth (alpha) channel is ignored. Because every image is a
// reflectance, values are clamped to [0, 1]; a NaN, an infinity or a negative value is an error.
// Throws SceneError "<where>cannot read texture '<name>': <why>" on any failure.
std::shared_ptr<const Image> load_image(const FileGate& gate, const std::string& path, bool raw, const std::string& where,
                                        const std::string& written = {});
// load_image of encoded bytes in memory (an embedded image), named `name` in messages.
std::shared_ptr<const Image> load_image_bytes(const std::string& bytes, const std::string& name, bool raw,
                                              const std::string& where);

}  // namespace omega
