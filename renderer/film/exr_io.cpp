// OpenEXR output and input. Everything goes through memory streams so the file writer can fsync
// and rename (OpenEXR's own file streams cannot), and tiles can travel over the network.
#include <fcntl.h>
#include <unistd.h>

#include <Iex.h>
#include <ImfChannelList.h>
#include <ImfCheckFile.h>
#include <ImfDoubleAttribute.h>
#include <ImfFloatAttribute.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfIO.h>
#include <ImfInputFile.h>
#include <ImfIntAttribute.h>
#include <ImfOutputFile.h>
#include <ImfStringAttribute.h>
#include <ImfThreading.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cstdio>
#include <cstring>
#include <stdexcept>
#include <string>

#include "film/film.h"

namespace omega {

void set_exr_threads(int threads) { Imf::setGlobalThreadCount(std::max(0, threads)); }

namespace {

class MemOStream final : public Imf::OStream {
public:
    MemOStream() : Imf::OStream("<memory>") {}
    void write(const char c[], int n) override {
        // OpenEXR seeks back to fill in the offset table, so writes may land before the end.
        if (pos_ + size_t(n) > buf_.size()) buf_.resize(pos_ + size_t(n));
        std::memcpy(buf_.data() + pos_, c, size_t(n));
        pos_ += size_t(n);
    }
    uint64_t tellp() override { return pos_; }
    void seekp(uint64_t pos) override { pos_ = pos; }
    std::vector<uint8_t> take() { return std::move(buf_); }

private:
    std::vector<uint8_t> buf_;
    size_t pos_ = 0;
};

class MemIStream final : public Imf::IStream {
public:
    explicit MemIStream(std::span<const uint8_t> b) : Imf::IStream("<memory>"), b_(b) {}
    bool read(char c[], int n) override {
        // Bounds are checked without forming pos_ + n, which a hostile seek could overflow.
        if (n < 0 || pos_ > b_.size() || uint64_t(n) > b_.size() - pos_)
            throw Iex::InputExc("unexpected end of EXR data");
        std::memcpy(c, b_.data() + pos_, size_t(n));
        pos_ += uint64_t(n);
        return pos_ < b_.size();
    }
    uint64_t tellg() override { return pos_; }
    void seekg(uint64_t pos) override { pos_ = pos; }
    void clear() override {}

private:
    std::span<const uint8_t> b_;
    uint64_t pos_ = 0;
};

const char* const kRgb[3] = {"R", "G", "B"};
const char* const kVar[3] = {"var.R", "var.G", "var.B"};

// Encodes six float planes (R G B var.R var.G var.B, each rect-sized, row-major) with the
// data window rect inside a width x height display window.
std::vector<uint8_t> encode_planes(int width, int height, const Rect& rect, const std::vector<float>& planes,
                                   const ExrMeta& meta) {
    const Imath::Box2i display({0, 0}, {width - 1, height - 1});
    const Imath::Box2i data({rect.x0, rect.y0}, {rect.x1 - 1, rect.y1 - 1});
    Imf::Header header(display, data, 1.f, Imath::V2f(0, 0), 1.f, Imf::INCREASING_Y,
                       meta.compress ? Imf::ZIP_COMPRESSION : Imf::NO_COMPRESSION);
    for (int k = 0; k < 3; ++k) {
        header.channels().insert(kRgb[k], Imf::Channel(Imf::FLOAT));
        header.channels().insert(kVar[k], Imf::Channel(Imf::FLOAT));
    }
    // The EXR int is 32-bit; a render never gets near 2^31 spp, so clamping only guards nonsense.
    header.insert("omega.spp", Imf::IntAttribute(int(std::clamp<long long>(meta.spp, INT_MIN, INT_MAX))));
    header.insert("omega.time_s", Imf::DoubleAttribute(meta.time_s));
    header.insert("omega.integrator", Imf::StringAttribute(meta.integrator));
    // 64-bit values as decimal strings: EXR has no 64-bit integer attribute.
    header.insert("omega.seed", Imf::StringAttribute(std::to_string(meta.seed)));
    header.insert("omega.nonfinite", Imf::StringAttribute(std::to_string(meta.nonfinite)));
    std::string warnings;
    for (size_t i = 0; i < meta.warnings.size(); ++i) warnings += (i ? "\n" : "") + meta.warnings[i];
    header.insert("omega.warnings", Imf::StringAttribute(warnings));
    header.insert("omega.rel_error", Imf::DoubleAttribute(meta.rel_error));
    for (const auto& [name, value] : meta.attributes) header.insert(name, Imf::StringAttribute(value));

    const size_t w = size_t(rect.width()), h = size_t(rect.height()), area = w * h;
    Imf::FrameBuffer fb;
    // OpenEXR's slices take non-const pointers but only read them when writing.
    float* base = const_cast<float*>(planes.data());
    for (int k = 0; k < 3; ++k) {
        fb.insert(kRgb[k], Imf::Slice::Make(Imf::FLOAT, base + size_t(k) * area, data, sizeof(float),
                                            sizeof(float) * w));
        fb.insert(kVar[k], Imf::Slice::Make(Imf::FLOAT, base + size_t(3 + k) * area, data, sizeof(float),
                                            sizeof(float) * w));
    }
    std::vector<std::string> names;  // kept alive: the header and frame buffer refer to them
    names.reserve(meta.layers.size() * 3);
    for (const auto& layer : meta.layers) {
        if (layer.rgb.size() != 3 * area) throw std::invalid_argument("EXR layer '" + layer.name + "' has the wrong size");
        for (int k = 0; k < 3; ++k) {
            names.push_back(layer.name + "." + kRgb[k]);
            header.channels().insert(names.back(), Imf::Channel(Imf::FLOAT));
            fb.insert(names.back(), Imf::Slice::Make(Imf::FLOAT, const_cast<float*>(layer.rgb.data()) + k, data,
                                                     3 * sizeof(float), 3 * sizeof(float) * w));
        }
    }
    for (const auto& u : meta.uint_channels) {
        if (u.data.size() != area) throw std::invalid_argument("EXR channel '" + u.name + "' has the wrong size");
        header.channels().insert(u.name, Imf::Channel(Imf::UINT));
        fb.insert(u.name, Imf::Slice::Make(Imf::UINT, const_cast<uint32_t*>(u.data.data()), data, sizeof(uint32_t),
                                           sizeof(uint32_t) * w));
    }
    MemOStream os;
    {
        // The destructor writes the final line-offset table, so it must run before take().
        Imf::OutputFile out(os, header);
        out.setFrameBuffer(fb);
        out.writePixels(int(h));
    }
    return os.take();
}

std::vector<uint8_t> encode(const Film& film, const Rect& rect, const ExrMeta& meta) {
    const Rect c = film.crop();
    if (rect.x0 < c.x0 || rect.y0 < c.y0 || rect.x1 > c.x1 || rect.y1 > c.y1 || rect.width() <= 0 ||
        rect.height() <= 0)
        throw std::invalid_argument("EXR rect is empty or outside the film crop");

    const size_t w = size_t(rect.width()), area = w * size_t(rect.height());
    std::vector<float> planes(6 * area);  // R G B var.R var.G var.B, one plane each
    for (int y = rect.y0; y < rect.y1; ++y)
        for (int x = rect.x0; x < rect.x1; ++x) {
            const PixelStats s = film.pixel(x, y);
            const size_t i = size_t(y - rect.y0) * w + size_t(x - rect.x0);
            for (int k = 0; k < 3; ++k) {
                planes[size_t(k) * area + i] = float(s.mean[k]);
                planes[size_t(3 + k) * area + i] = float(s.var_of_mean[k]);
            }
        }
    return encode_planes(film.width(), film.height(), rect, planes, meta);
}

std::string number_text(double v) {
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}
std::string number_text(float v) {
    char buf[64];
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    return std::string(buf, r.ptr);
}

// UINT channels are read only from files (partial renders); network bytes never need them, and
// a hostile tile could declare thousands. A part holds 16 for its film and 16 per AOV (at most
// 32 AOVs, pathspace/lpe.h).
constexpr int kMaxUintChannels = 16 * (1 + 32);

ExrImage read_image(Imf::InputFile& file, long long max_pixels, bool with_uint) {
    const Imf::Header& header = file.header();
    // A truncated file would otherwise read as zeros (or throw mid-way for some compressions).
    if (!file.isComplete()) throw std::runtime_error("file is incomplete");
    const Imath::Box2i dw = header.dataWindow(), disp = header.displayWindow();
    const long long w = (long long)dw.max.x - dw.min.x + 1, h = (long long)dw.max.y - dw.min.y + 1;
    if (w <= 0 || h <= 0) throw std::runtime_error("empty data window");
    if (w > max_pixels / h)
        throw std::runtime_error("data window " + std::to_string(w) + "x" + std::to_string(h) + " exceeds " +
                                 std::to_string(max_pixels) + " pixels");
    ExrImage img;
    img.width = int(w);
    img.height = int(h);
    img.x0 = dw.min.x;
    img.y0 = dw.min.y;
    img.display_width = int(std::clamp<long long>((long long)disp.max.x - disp.min.x + 1, 0, INT_MAX));
    img.display_height = int(std::clamp<long long>((long long)disp.max.y - disp.min.y + 1, 0, INT_MAX));

    const Imf::ChannelList& ch = header.channels();
    auto usable = [&](const char* name) {
        const Imf::Channel* c = ch.findChannel(name);
        if (c && (c->xSampling != 1 || c->ySampling != 1))
            throw std::runtime_error(std::string("channel ") + name + " is subsampled");
        return c != nullptr;
    };
    for (const char* n : kRgb)
        if (!usable(n)) throw std::runtime_error(std::string("no channel ") + n);
    const bool has_var = usable(kVar[0]) && usable(kVar[1]) && usable(kVar[2]);

    const size_t area = size_t(w) * size_t(h);
    img.rgb.resize(3 * area);
    if (has_var) img.var.resize(3 * area);
    Imf::FrameBuffer fb;
    const size_t xs = 3 * sizeof(float), ys = xs * size_t(w);
    for (int k = 0; k < 3; ++k) {
        fb.insert(kRgb[k], Imf::Slice::Make(Imf::FLOAT, &img.rgb[size_t(k)], dw, xs, ys));
        if (has_var) fb.insert(kVar[k], Imf::Slice::Make(Imf::FLOAT, &img.var[size_t(k)], dw, xs, ys));
    }
    for (auto it = ch.begin(); with_uint && it != ch.end(); ++it) {
        if (it.channel().type != Imf::UINT || it.channel().xSampling != 1 || it.channel().ySampling != 1) continue;
        if (img.uint_channels.size() >= size_t(kMaxUintChannels))
            throw std::runtime_error("more than " + std::to_string(kMaxUintChannels) + " UINT channels");
        auto& plane = img.uint_channels[it.name()];
        plane.resize(area);
        fb.insert(it.name(), Imf::Slice::Make(Imf::UINT, plane.data(), dw, sizeof(uint32_t), sizeof(uint32_t) * size_t(w)));
    }
    file.setFrameBuffer(fb);
    file.readPixels(dw.min.y, dw.max.y);

    for (auto it = header.begin(); it != header.end(); ++it) {
        const Imf::Attribute& a = it.attribute();
        if (auto* s = dynamic_cast<const Imf::StringAttribute*>(&a))
            img.attributes[it.name()] = s->value();
        else if (auto* i = dynamic_cast<const Imf::IntAttribute*>(&a))
            img.attributes[it.name()] = std::to_string(i->value());
        else if (auto* f = dynamic_cast<const Imf::FloatAttribute*>(&a))
            img.attributes[it.name()] = number_text(f->value());
        else if (auto* d = dynamic_cast<const Imf::DoubleAttribute*>(&a))
            img.attributes[it.name()] = number_text(d->value());
    }
    return img;
}

}  // namespace

// Writes all of bytes to path via path.tmp, fsync and rename, so a crash leaves the old file or
// the new one. The directory is synced too so the rename itself survives a power cut.
void write_file_atomic(const std::string& path, std::span<const uint8_t> bytes) {
    const std::string tmp = path + ".tmp";
    auto fail = [&](const char* what) {
        const int err = errno;
        ::unlink(tmp.c_str());
        throw std::runtime_error("write_exr: " + path + ": " + what + ": " + std::strerror(err));
    };
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd < 0) {
        const int err = errno;
        throw std::runtime_error("write_exr: " + path + ": cannot create " + tmp + ": " + std::strerror(err));
    }
    size_t done = 0;
    while (done < bytes.size()) {
        const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
        if (n < 0) {
            if (errno == EINTR) continue;
            ::close(fd);
            fail("write");
        }
        done += size_t(n);
    }
    if (::fsync(fd) != 0) {
        ::close(fd);
        fail("fsync");
    }
    if (::close(fd) != 0) fail("close");
    if (std::rename(tmp.c_str(), path.c_str()) != 0) fail("rename");
    const size_t slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : (slash == 0 ? "/" : path.substr(0, slash));
    const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dfd >= 0) {
        ::fsync(dfd);  // best effort: the file is complete and in place either way
        ::close(dfd);
    }
}

void write_exr(const std::string& path, const Film& film, const ExrMeta& meta) {
    std::vector<uint8_t> bytes;
    try {
        bytes = encode(film, film.crop(), meta);
    } catch (const std::exception& e) {
        throw std::runtime_error("write_exr: " + path + ": " + e.what());
    }
    write_file_atomic(path, bytes);
}

std::vector<uint8_t> encode_exr_image(const ExrImage& img, const ExrMeta& meta) {
    const Rect rect{img.x0, img.y0, img.x0 + img.width, img.y0 + img.height};
    const size_t area = size_t(img.width) * size_t(img.height);
    if (img.width <= 0 || img.height <= 0 || img.x0 < 0 || img.y0 < 0 || rect.x1 > img.display_width ||
        rect.y1 > img.display_height || img.rgb.size() != 3 * area || (!img.var.empty() && img.var.size() != 3 * area))
        throw std::invalid_argument("encode_exr_image: inconsistent image size or data window");
    std::vector<float> planes(6 * area, 0.f);
    for (size_t i = 0; i < area; ++i)
        for (size_t k = 0; k < 3; ++k) {
            planes[k * area + i] = img.rgb[3 * i + k];
            if (!img.var.empty()) planes[(3 + k) * area + i] = img.var[3 * i + k];
        }
    return encode_planes(img.display_width, img.display_height, rect, planes, meta);
}

ExrImage read_exr(const std::string& path, long long max_pixels) {
    try {
        Imf::InputFile file(path.c_str());
        return read_image(file, max_pixels, true);
    } catch (const std::exception& e) {
        throw std::runtime_error("read_exr: " + path + ": " + e.what());
    }
}

std::vector<float> read_exr_layer(const std::string& path, const std::string& layer) {
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        const Imath::Box2i dw = header.dataWindow();
        const size_t w = size_t(dw.max.x - dw.min.x + 1), h = size_t(dw.max.y - dw.min.y + 1);
        std::vector<float> out(3 * w * h);
        Imf::FrameBuffer fb;
        for (int k = 0; k < 3; ++k) {
            std::string name = layer;
            name += '.';
            name += "RGB"[k];
            const Imf::Channel* c = header.channels().findChannel(name);
            if (!c || c->type != Imf::FLOAT || c->xSampling != 1 || c->ySampling != 1)
                throw std::runtime_error("no float channel " + name);
            fb.insert(name, Imf::Slice::Make(Imf::FLOAT, &out[size_t(k)], dw, 3 * sizeof(float), 3 * sizeof(float) * w));
        }
        file.setFrameBuffer(fb);
        file.readPixels(dw.min.y, dw.max.y);
        return out;
    } catch (const std::exception& e) {
        throw std::runtime_error("read_exr_layer: " + path + ": " + e.what());
    }
}

std::vector<uint8_t> encode_exr_tile(const Film& film, const Rect& rect, const ExrMeta& meta) {
    return encode(film, rect, meta);
}

namespace {

// Walks the EXR header(s) and checks that every attribute's declared size fits in the bytes we
// hold. OpenEXR (3.1) allocates an attribute's declared size before reading it, so a 30-byte
// input claiming a 2 GiB string attribute would cost 2 GiB (found by fuzz/fuzz_tile_exr).
void check_exr_header_sizes(std::span<const uint8_t> b) {
    auto bad = [](const char* what) { throw std::runtime_error(std::string("invalid EXR header: ") + what); };
    if (b.size() < 8 || b[0] != 0x76 || b[1] != 0x2f || b[2] != 0x31 || b[3] != 0x01) bad("not an EXR file");
    const bool multipart = (b[5] & 0x10) != 0;  // flags bit 12 (0x1000): bytes 4..7 little-endian
    size_t p = 8;
    auto cstring = [&](size_t max_len) {
        size_t start = p;
        while (p < b.size() && b[p] != 0) {
            if (p - start >= max_len) bad("name too long");
            ++p;
        }
        if (p >= b.size()) bad("truncated");
        return p++ - start;  // length, and skip the NUL
    };
    for (int headers = 0;; ++headers) {
        if (headers > 1024) bad("too many parts");
        for (int attrs = 0;; ++attrs) {
            if (attrs > 100000) bad("too many attributes");
            if (cstring(255) == 0) break;  // end of this header
            if (cstring(255) == 0) bad("empty attribute type");
            if (b.size() - p < 4) bad("truncated");
            const uint32_t size = uint32_t(b[p]) | uint32_t(b[p + 1]) << 8 | uint32_t(b[p + 2]) << 16 | uint32_t(b[p + 3]) << 24;
            p += 4;
            if (size > b.size() - p) bad("an attribute is larger than the file");
            p += size;
        }
        if (!multipart || p >= b.size() || b[p] == 0) return;
    }
}

}  // namespace

ExrImage decode_exr_memory(std::span<const uint8_t> bytes, long long max_pixels) {
    try {
        check_exr_header_sizes(bytes);
        // OpenEXR's fuzz-tested validator: it reads the data through every API with memory
        // limits, so inputs that could drive the decoders into trouble are turned away first.
        if (Imf::checkOpenEXRFile(reinterpret_cast<const char*>(bytes.data()), bytes.size(), true, true, true))
            throw std::runtime_error("invalid EXR data");
        MemIStream is(bytes);
        Imf::InputFile file(is);
        return read_image(file, max_pixels, false);
    } catch (const std::exception& e) {
        throw std::runtime_error(std::string("decode_exr_memory: ") + e.what());
    }
}

}  // namespace omega
