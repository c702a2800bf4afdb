#include "texture/image.h"

#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "io/file_gate.h"
#include "io/image_library.h"
#include "scene/scene_error.h"

namespace omega {

namespace {

// Image files are read whole into memory; past this a texture is not a reflectance map.
constexpr std::uint64_t kMaxImageFileBytes = std::uint64_t(1) << 30;

bool starts_with(const std::string& s, std::string_view magic) {
    return s.size() >= magic.size() && std::memcmp(s.data(), magic.data(), magic.size()) == 0;
}

// OIIO's format name for the bytes, by magic number; else the extension's (OIIO maps it).
std::string format_of(const std::string& bytes, const std::string& path) {
    if (starts_with(bytes, "\x89PNG\r\n\x1a\n")) return "png";
    if (starts_with(bytes, "\xff\xd8\xff")) return "jpeg";
    if (starts_with(bytes, "\x76\x2f\x31\x01")) return "openexr";
    if (starts_with(bytes, "#?RADIANCE") || starts_with(bytes, "#?RGBE")) return "hdr";
    if (starts_with(bytes, "PF\n") || starts_with(bytes, "Pf\n") || starts_with(bytes, "PF\r") || starts_with(bytes, "Pf\r"))
        return "pnm";
    if (starts_with(bytes, "BM")) return "bmp";
    if (starts_with(bytes, "II*\0") || starts_with(bytes, std::string_view("MM\0*", 4))) return "tiff";
    std::string ext = std::filesystem::path(path).extension().string();
    return ext.empty() ? std::string() : ext.substr(1);
}

}  // namespace

float srgb_to_linear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

ImagePixels decode_image(const FileGate& gate, const std::string& path, const std::string& written,
                         const std::string& where, const std::string& what) {
    std::string bytes;
    try {
        bytes = gate.read(path, kMaxImageFileBytes, written);
    } catch (const FileRefused& e) {
        throw SceneError(where + e.what());
    }
    return decode_image_bytes(bytes, path, written.empty() ? gate.shown(path) : written, where, what);
}

ImagePixels decode_image_bytes(const std::string& bytes, const std::string& path, const std::string& name,
                               const std::string& where, const std::string& what) {
    auto fail = [&](const std::string& why) -> SceneError {
        return SceneError(fmt::format("{}cannot read {} '{}': {}", where, what, name, why));
    };
    if (bytes.size() > kMaxImageFileBytes) throw fail("larger than 1 GiB");
    const std::string format = format_of(bytes, path);
    if (format.empty()) throw fail("unknown image format");
    const ImageLibrary* lib;
    try {
        lib = &image_library();
    } catch (const std::runtime_error& e) {
        throw fail(e.what());
    }
    ImagePixels out;
    if (std::string why = lib->decode(bytes, format, path, name, out); !why.empty()) throw fail(why);
    return out;
}

namespace {

// Decoded pixels as a reflectance texture (load_image's rules); `name` for messages.
std::shared_ptr<const Image> texture_of(const ImagePixels& px, bool raw, const std::string& where, const std::string& name) {
    auto fail = [&](const std::string& why) -> SceneError {
        return SceneError(fmt::format("{}cannot read texture '{}': {}", where, name, why));
    };
    const bool decode_srgb = !raw && !px.is_float;
    const int nc = px.channels;
    auto img = std::make_shared<Image>();
    img->width = px.width;
    img->height = px.height;
    img->texels.resize(std::size_t(px.width) * std::size_t(px.height));
    // Grey (1 channel) and grey + alpha (2) replicate the first channel; RGB(A) uses the first three.
    const bool colour = nc >= 3;
    for (std::size_t i = 0; i < img->texels.size(); ++i) {
        const float* p = &px.data[i * std::size_t(nc)];
        Rgb c = colour ? Rgb{p[0], p[1], p[2]} : Rgb(p[0]);
        for (int ch = 0; ch < 3; ++ch) {
            float v = c[ch];
            if (!std::isfinite(v) || v < 0)
                throw fail(fmt::format("texel ({}, {}) has the value {} (reflectance must be finite and >= 0)",
                                       i % std::size_t(px.width), i / std::size_t(px.width), v));
            if (decode_srgb) v = srgb_to_linear(v);
            c[ch] = std::min(v, 1.f);
        }
        img->texels[i] = c;
    }
    return img;
}

}  // namespace

std::shared_ptr<const Image> load_image(const FileGate& gate, const std::string& path, bool raw, const std::string& where,
                                        const std::string& written) {
    return texture_of(decode_image(gate, path, written, where, "texture"), raw, where,
                      written.empty() ? gate.shown(path) : written);
}

std::shared_ptr<const Image> load_image_bytes(const std::string& bytes, const std::string& name, bool raw,
                                              const std::string& where) {
    return texture_of(decode_image_bytes(bytes, name, name, where, "texture"), raw, where, name);
}

}  // namespace omega
