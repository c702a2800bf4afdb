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
    auto oiio_error = [&] {
        std::string err = buf.geterror();
        return fail(err.empty() ? "unknown image format" : err);
    };
    // The header first: the size is checked before any pixel is decoded.
    if (!buf.init_spec(path, 0, 0)) throw oiio_error();
    {
        const OIIO::ImageSpec& ns = buf.nativespec();
        if (ns.width <= 0 || ns.height <= 0 || ns.nchannels <= 0) throw fail("the image is empty");
        if (ns.depth > 1) throw fail("3D images are not textures");
        // 12 bytes a texel once decoded: 8192 x 8192 is 800 MB; past that a small PNG could exhaust memory.
        if (size_t(ns.width) * size_t(ns.height) > (size_t(1) << 26))
            throw fail(fmt::format("{} x {} texels is larger than 8192 x 8192", ns.width, ns.height));
    }
    // Subimage 0, mip level 0, converted to float while reading.
    if (!buf.read(0, 0, true, OIIO::TypeDesc::FLOAT)) throw oiio_error();
    const OIIO::ImageSpec& spec = buf.spec();
    const int nc = spec.nchannels;
    // The file's own pixel type: spec() already says FLOAT after the converting read.
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
