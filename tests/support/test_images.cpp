#include "test_images.h"

#include <OpenImageIO/imageio.h>

#include <cmath>
#include <filesystem>
#include <stdexcept>

namespace omega::test {

namespace {

void write(const std::string& path, int w, int h, int channels, OIIO::TypeDesc type, const void* data) {
    std::filesystem::create_directories(std::filesystem::path(path).parent_path());
    auto out = OIIO::ImageOutput::create(path);
    if (!out) throw std::runtime_error("no image writer for " + path);
    OIIO::ImageSpec spec(w, h, channels, type);
    spec.attribute("oiio:UnassociatedAlpha", 1);  // write colour as given, not divided by alpha
    if (!out->open(path, spec) || !out->write_image(type, data) || !out->close())
        throw std::runtime_error("cannot write " + path + ": " + out->geterror());
}

}  // namespace

void write_image_u8(const std::string& path, int w, int h, int channels, const std::vector<uint8_t>& data) {
    if (data.size() != size_t(w) * size_t(h) * size_t(channels)) throw std::logic_error("write_image_u8: size");
    write(path, w, h, channels, OIIO::TypeDesc::UINT8, data.data());
}

void write_image_f32(const std::string& path, int w, int h, int channels, const std::vector<float>& data) {
    if (data.size() != size_t(w) * size_t(h) * size_t(channels)) throw std::logic_error("write_image_f32: size");
    write(path, w, h, channels, OIIO::TypeDesc::FLOAT, data.data());
}

double srgb8_to_linear(int c) {
    double v = c / 255.0;
    return v <= 0.04045 ? v / 12.92 : std::pow((v + 0.055) / 1.055, 2.4);
}

}  // namespace omega::test
