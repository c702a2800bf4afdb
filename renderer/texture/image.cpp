#include "texture/image.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>
#include <fmt/format.h>

#include <cmath>
#include <cstring>
#include <filesystem>

#include "io/file_gate.h"
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
    auto in = format.empty() ? nullptr : OIIO::ImageInput::create(format, false);
    (void)OIIO::geterror();  // create() leaves a message behind when it finds no reader
    if (!in) throw fail("unknown image format");
    if (!in->supports("ioproxy")) throw fail(fmt::format("{} images cannot be read from memory", in->format_name()));
    OIIO::Filesystem::IOMemReader proxy(bytes.data(), bytes.size());
    in->set_ioproxy(&proxy);
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);  // colour as stored: without this OIIO premultiplies PNG colour by its alpha
    OIIO::ImageSpec spec;
    // The name is only for messages: /proc cannot hold it, so a reader that ignored the proxy
    // would find nothing.
    const std::string fake = "/proc/omega-in-memory/" + std::filesystem::path(path).filename().string();
    auto oiio_error = [&] {
        std::string err = in->geterror();
        for (std::size_t pos; (pos = err.find(fake)) != std::string::npos;) err.replace(pos, fake.size(), name);
        return fail(err.empty() ? "not a valid " + format + " image" : err);
    };
    if (!in->open(fake, spec, config)) throw oiio_error();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) throw fail("the image is empty");
    if (spec.depth > 1) throw fail("3D images are not textures");
    // 12 bytes a texel once decoded: 8192 x 8192 is 800 MB; past that a small PNG could exhaust memory.
    if (std::size_t(spec.width) * std::size_t(spec.height) > (std::size_t(1) << 26))
        throw fail(fmt::format("{} x {} texels is larger than 8192 x 8192", spec.width, spec.height));
    if (spec.nchannels > 64) throw fail(fmt::format("{} channels", spec.nchannels));
    ImagePixels out;
    out.width = spec.width;
    out.height = spec.height;
    out.channels = spec.nchannels;
    const auto base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
    out.is_float = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
    out.data.resize(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(spec.nchannels));
    // Subimage 0, mip level 0, every channel, converted to float while reading.
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out.data.data())) throw oiio_error();
    in->close();
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
