#include "texture/image.h"

#include <OpenImageIO/imagebuf.h>
#include <fmt/format.h>

#include <cmath>

#include "scene/scene_error.h"

namespace omega {

float srgb_to_linear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

std::shared_ptr<const Image> load_image(const std::string& path, bool raw, const std::string& where) {
    auto fail = [&](const std::string& why) -> SceneError {
        return SceneError(fmt::format("{}cannot read texture '{}': {}", where, path, why));
    };
    // Colour as stored: without this OIIO premultiplies PNG colour by its alpha.
    OIIO::ImageSpec config;
    config.attribute("oiio:UnassociatedAlpha", 1);
    OIIO::ImageBuf buf(path, 0, 0, nullptr, &config);
    // Subimage 0, mip level 0, converted to float while reading.
    if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT)) {
        std::string err = buf.geterror();
        throw fail(err.empty() ? "unknown image format" : err);
    }
    const OIIO::ImageSpec& spec = buf.spec();
    // The file's own pixel type: spec() already says FLOAT after the converting read.
    const int nc = spec.nchannels;
    if (spec.width <= 0 || spec.height <= 0 || nc <= 0) throw fail("the image is empty");
    if (spec.depth > 1) throw fail("3D images are not textures");
    if (size_t(spec.width) * size_t(spec.height) > (size_t(1) << 28)) throw fail("the image is too large");
    const auto base = OIIO::TypeDesc::BASETYPE(buf.nativespec().format.basetype);
    const bool is_float = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
    const bool decode_srgb = !raw && !is_float;

    std::vector<float> px(size_t(spec.width) * size_t(spec.height) * size_t(nc));
    if (!buf.get_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, px.data())) throw fail(buf.geterror());

    auto img = std::make_shared<Image>();
    img->width = spec.width;
    img->height = spec.height;
    img->texels.resize(size_t(spec.width) * size_t(spec.height));
    // Grey (1 channel) and grey + alpha (2) replicate the first channel; RGB(A) uses the first three.
    const bool colour = nc >= 3;
    for (size_t i = 0; i < img->texels.size(); ++i) {
        const float* p = &px[i * size_t(nc)];
        Rgb c = colour ? Rgb{p[0], p[1], p[2]} : Rgb(p[0]);
        for (int ch = 0; ch < 3; ++ch) {
            float v = c[ch];
            if (!std::isfinite(v) || v < 0)
                throw fail(fmt::format("texel ({}, {}) has the value {} (reflectance must be finite and >= 0)",
                                       i % size_t(spec.width), i / size_t(spec.width), v));
            if (decode_srgb) v = srgb_to_linear(v);
            c[ch] = std::min(v, 1.f);
        }
        img->texels[i] = c;
    }
    return img;
}

}  // namespace omega
