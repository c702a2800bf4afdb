#include "tile_canvas.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <sstream>

#include "client_error.h"

namespace omega::client {

ExrMeta meta_from_attributes(const std::map<std::string, std::string>& a) {
    ExrMeta m;
    auto get = [&](const char* k) -> const std::string* {
        auto it = a.find(k);
        return it == a.end() ? nullptr : &it->second;
    };
    if (auto* v = get("omega.spp")) m.spp = std::strtoll(v->c_str(), nullptr, 10);
    if (auto* v = get("omega.time_s")) m.time_s = std::strtod(v->c_str(), nullptr);
    if (auto* v = get("omega.integrator")) m.integrator = *v;
    if (auto* v = get("omega.seed")) m.seed = std::strtoull(v->c_str(), nullptr, 10);
    if (auto* v = get("omega.nonfinite")) m.nonfinite = std::strtoull(v->c_str(), nullptr, 10);
    if (auto* v = get("omega.rel_error")) m.rel_error = std::strtod(v->c_str(), nullptr);
    if (auto* v = get("omega.warnings"); v && !v->empty()) {
        std::stringstream ss(*v);
        std::string line;
        while (std::getline(ss, line)) m.warnings.push_back(line);
    }
    return m;
}

bool TileCanvas::apply(const protocol::Tile& t) {
    const Key key{t.rect.x0, t.rect.y0, t.rect.x1, t.rect.y1};
    if (auto it = versions_.find(key); it != versions_.end() && it->second >= t.version) return false;
    ExrImage img;
    try {
        img = decode_exr_memory(std::span(reinterpret_cast<const uint8_t*>(t.exr.data()), t.exr.size()));
    } catch (const std::exception& e) {
        throw ClientError(kExitInternal, fmt::format("tile [{}, {}, {}, {}]: {}", t.rect.x0, t.rect.y0, t.rect.x1,
                                                     t.rect.y1, e.what()));
    }
    if (img.x0 != int(t.rect.x0) || img.y0 != int(t.rect.y0) || img.x0 + img.width != int(t.rect.x1) ||
        img.y0 + img.height != int(t.rect.y1))
        throw ClientError(kExitInternal, fmt::format("tile [{}, {}, {}, {}]: its EXR covers another rectangle",
                                                     t.rect.x0, t.rect.y0, t.rect.x1, t.rect.y1));
    if (versions_.empty() && width_ == 0) {
        // The client's limits: 65536 pixels a side (a row is then at most 768 KiB) and 2^28 in
        // all, beyond any film omegad's max_resolution lets through by default (16384 a side).
        if (img.display_width <= 0 || img.display_height <= 0 || img.display_width > (1 << 16) ||
            img.display_height > (1 << 16) || (long long)img.display_width * img.display_height > (1LL << 28))
            throw ClientError(kExitInternal, "tile: bad film size");
        width_ = img.display_width;
        height_ = img.display_height;
        rgb_.assign(size_t(height_), {});
        var_.assign(size_t(height_), {});
        bx0_ = img.x0;
        by0_ = img.y0;
        bx1_ = img.x0 + img.width;
        by1_ = img.y0 + img.height;
    }
    if (img.display_width != width_ || img.display_height != height_ || img.x0 + img.width > width_ ||
        img.y0 + img.height > height_)
        throw ClientError(kExitInternal, "tile: film size differs from earlier tiles'");
    for (int y = 0; y < img.height; ++y) {
        std::vector<float>& rgb = row(rgb_, img.y0 + y);
        std::vector<float>& var = row(var_, img.y0 + y);
        for (int x = 0; x < img.width; ++x) {
            const size_t src = 3 * (size_t(y) * size_t(img.width) + size_t(x));
            const size_t dst = 3 * size_t(img.x0 + x);
            for (int k = 0; k < 3; ++k) {
                rgb[dst + size_t(k)] = img.rgb[src + size_t(k)];
                var[dst + size_t(k)] = img.var.empty() ? 0.f : img.var[src + size_t(k)];
            }
        }
    }
    bx0_ = std::min(bx0_, img.x0);
    by0_ = std::min(by0_, img.y0);
    bx1_ = std::max(bx1_, img.x0 + img.width);
    by1_ = std::max(by1_, img.y0 + img.height);
    versions_[key] = t.version;
    // The attributes (spp, time, error) of the most advanced tile describe the image best.
    const std::tuple<uint64_t, uint64_t, uint64_t> rank{t.pass, t.spp, t.version};
    if (!have_meta_ || rank >= newest_) {
        newest_ = rank;
        have_meta_ = true;
        meta_ = meta_from_attributes(img.attributes);
    }
    return true;
}

ExrImage TileCanvas::image() const {
    ExrImage img;
    if (versions_.empty()) return img;
    img.display_width = width_;
    img.display_height = height_;
    img.x0 = bx0_;
    img.y0 = by0_;
    img.width = bx1_ - bx0_;
    img.height = by1_ - by0_;
    img.rgb.reserve(size_t(img.width) * size_t(img.height) * 3);
    img.var.reserve(img.rgb.capacity());
    const size_t n = 3 * size_t(img.width);
    for (int y = by0_; y < by1_; ++y) {
        const auto& r = rgb_[size_t(y)];
        const auto& v = var_[size_t(y)];
        if (r.empty()) {
            img.rgb.insert(img.rgb.end(), n, 0.f);
            img.var.insert(img.var.end(), n, 0.f);
            continue;
        }
        const long a = long(3 * size_t(bx0_));
        img.rgb.insert(img.rgb.end(), r.begin() + a, r.begin() + a + long(n));
        img.var.insert(img.var.end(), v.begin() + a, v.begin() + a + long(n));
    }
    return img;
}

std::vector<float>& TileCanvas::row(std::vector<std::vector<float>>& rows, int y) {
    std::vector<float>& r = rows[size_t(y)];
    if (r.empty()) r.assign(3 * size_t(width_), 0.f);
    return r;
}

std::vector<uint8_t> TileCanvas::encode() const {
    if (versions_.empty()) throw std::runtime_error("no tile received yet");
    return encode_exr_image(image(), meta_);
}

void TileCanvas::write(const std::string& path) const {
    const auto bytes = encode();
    write_file_atomic(path, bytes);
}

}  // namespace omega::client
