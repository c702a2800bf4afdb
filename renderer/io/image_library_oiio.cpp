// libomega_images.so: every call into OpenImageIO (see image_library.h). Built as a module, not
// part of omega_renderer, so no program loads OpenImageIO until it needs an image.
#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include <filesystem>
#include <limits>

#include "io/image_library.h"

namespace omega {

namespace {

namespace IBA = OIIO::ImageBufAlgo;

std::string decode(const std::string& bytes, const std::string& format, const std::string& path, const std::string& name,
                   ImagePixels& out) {
    auto in = format.empty() ? nullptr : OIIO::ImageInput::create(format, false);
    (void)OIIO::geterror();  // create() leaves a message behind when it finds no reader
    if (!in) return "unknown image format";
    if (!in->supports("ioproxy")) return std::string(in->format_name()) + " images cannot be read from memory";
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
        return err.empty() ? "not a valid " + format + " image" : err;
    };
    if (!in->open(fake, spec, config)) return oiio_error();
    if (spec.width <= 0 || spec.height <= 0 || spec.nchannels <= 0) return "the image is empty";
    if (spec.depth > 1) return "3D images are not textures";
    // 12 bytes a texel once decoded: 8192 x 8192 is 800 MB; past that a small PNG could exhaust memory.
    if (std::size_t(spec.width) * std::size_t(spec.height) > (std::size_t(1) << 26))
        return std::to_string(spec.width) + " x " + std::to_string(spec.height) + " texels is larger than 8192 x 8192";
    if (spec.nchannels > 64) return std::to_string(spec.nchannels) + " channels";
    out.width = spec.width;
    out.height = spec.height;
    out.channels = spec.nchannels;
    const auto base = OIIO::TypeDesc::BASETYPE(spec.format.basetype);
    out.is_float = base == OIIO::TypeDesc::HALF || base == OIIO::TypeDesc::FLOAT || base == OIIO::TypeDesc::DOUBLE;
    out.data.resize(std::size_t(spec.width) * std::size_t(spec.height) * std::size_t(spec.nchannels));
    // Subimage 0, mip level 0, every channel, converted to float while reading.
    if (!in->read_image(0, 0, 0, spec.nchannels, OIIO::TypeDesc::FLOAT, out.data.data())) return oiio_error();
    in->close();
    return {};
}

OIIO::ImageBuf to_buf(const ImagePixels& px) {
    OIIO::ImageBuf buf(OIIO::ImageSpec(px.width, px.height, px.channels, OIIO::TypeDesc::FLOAT));
    buf.set_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, px.data.data());
    return buf;
}

void from_buf(const OIIO::ImageBuf& buf, ImagePixels& out) {
    const OIIO::ImageSpec& s = buf.spec();
    out.width = s.width;
    out.height = s.height;
    out.channels = s.nchannels;
    out.is_float = true;
    out.data.resize(std::size_t(s.width) * std::size_t(s.height) * std::size_t(s.nchannels));
    buf.get_pixels(buf.roi(), OIIO::TypeDesc::FLOAT, out.data.data());
}

std::string read_file(const std::string& path, ImagePixels& out) {
    OIIO::ImageBuf in(path);
    if (!in.read(0, 0, true, OIIO::TypeDesc::FLOAT)) return in.geterror();
    from_buf(in, out);
    return {};
}

std::string resize(const ImagePixels& in, int width, int height, const std::string& filter, ImagePixels& out) {
    OIIO::ImageBuf small(OIIO::ImageSpec(width, height, in.channels, OIIO::TypeDesc::FLOAT));
    if (!IBA::resize(small, to_buf(in), filter)) return "resize: " + small.geterror();
    from_buf(small, out);
    return {};
}

double channel_mean(const IBA::PixelStats& s) {
    double m = 0;
    for (float v : s.avg) m += v;
    return s.avg.empty() ? 0 : m / double(s.avg.size());
}

std::string compare(const ImagePixels& image, const ImagePixels& reference, double eps, double out[4]) {
    const OIIO::ImageBuf img = to_buf(image), ref = to_buf(reference);
    IBA::CompareResults cr = IBA::compare(img, ref, 1e30f, 1e30f);
    out[0] = cr.rms_error;
    OIIO::ImageBuf diff = IBA::sub(img, ref);
    OIIO::ImageBuf denom = IBA::add(IBA::mul(ref, ref), float(eps));
    out[1] = channel_mean(IBA::computePixelStats(IBA::div(IBA::mul(diff, diff), denom)));
    OIIO::ImageBuf adenom = IBA::add(IBA::abs(ref), float(eps));
    out[2] = channel_mean(IBA::computePixelStats(IBA::div(IBA::abs(diff), adenom)));
    double mi = channel_mean(IBA::computePixelStats(img)), mr = channel_mean(IBA::computePixelStats(ref));
    out[3] = mr != 0 ? mi / mr : std::numeric_limits<double>::quiet_NaN();
    return {};
}

std::string write_rgb8(const std::string& path, int width, int height, const unsigned char* rgb) {
    auto out = OIIO::ImageOutput::create(path);
    if (!out) return OIIO::geterror();
    const OIIO::ImageSpec spec(width, height, 3, OIIO::TypeDesc::UINT8);
    if (!out->open(path, spec) || !out->write_image(OIIO::TypeDesc::UINT8, rgb) || !out->close()) return out->geterror();
    return {};
}

const ImageLibrary kLibrary{kImageLibraryAbi, decode, read_file, resize, compare, write_rgb8};

}  // namespace

}  // namespace omega

extern "C" __attribute__((visibility("default"))) const omega::ImageLibrary* omega_image_library() { return &omega::kLibrary; }
