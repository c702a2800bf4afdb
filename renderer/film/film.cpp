#include "film/film.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <string>

namespace omega {

namespace {

Rect crop_of(const FilmDesc& d) {
    if (d.width <= 0 || d.height <= 0)
        throw std::invalid_argument("film size must be positive, got " + std::to_string(d.width) + "x" +
                                    std::to_string(d.height));
    if (!d.has_crop) return {0, 0, d.width, d.height};
    Rect r{d.crop[0], d.crop[1], d.crop[2], d.crop[3]};
    if (r.x0 < 0 || r.y0 < 0 || r.x1 > d.width || r.y1 > d.height || r.x0 >= r.x1 || r.y0 >= r.y1)
        throw std::invalid_argument("film crop [" + std::to_string(r.x0) + ", " + std::to_string(r.y0) + ", " +
                                    std::to_string(r.x1) + ", " + std::to_string(r.y1) +
                                    ") is empty or outside the film");
    return r;
}

}  // namespace

Film::Film(const FilmDesc& desc) : desc_(desc), filter_(desc), crop_(crop_of(desc)), px_(size_t(crop_.area())) {}

int Film::width() const { return desc_.width; }
int Film::height() const { return desc_.height; }
Rect Film::crop() const { return crop_; }

std::vector<Rect> Film::tiles(int tile_size) const {
    if (tile_size <= 0) throw std::invalid_argument("tile size must be positive");
    std::vector<Rect> out;
    for (int y = crop_.y0; y < crop_.y1; y += tile_size)
        for (int x = crop_.x0; x < crop_.x1; x += tile_size)
            out.push_back({x, y, std::min(x + tile_size, crop_.x1), std::min(y + tile_size, crop_.y1)});
    return out;
}

Vec2 Film::sample_position(int x, int y, Vec2 u) const {
    Vec2 d = filter_.sample(u);
    return {float(x) + 0.5f + d.x, float(y) + 0.5f + d.y};
}

size_t Film::index(int x, int y) const {
    // Cheap next to a path; a stray pixel would otherwise corrupt a neighbour silently.
    if (x < crop_.x0 || x >= crop_.x1 || y < crop_.y0 || y >= crop_.y1)
        throw std::out_of_range("pixel (" + std::to_string(x) + ", " + std::to_string(y) + ") outside the film crop");
    return size_t(y - crop_.y0) * size_t(crop_.width()) + size_t(x - crop_.x0);
}

void Film::add_sample(int x, int y, const Rgb& value) { add_weighted(x, y, Vec3d(value), 1.0); }

void Film::add_weighted(int x, int y, const Vec3d& value, double weight) { add_weighted_at(index(x, y), value, weight); }

PixelStats Film::pixel(int x, int y) const {
    const Accum& a = px_[index(x, y)];
    PixelStats s;
    s.n = a.n;
    s.mean = {a.mean[0], a.mean[1], a.mean[2]};
    if (a.n >= 2) {
        // Weighted samples x_b with weights n_b (batch sizes) each estimate the mean with
        // variance sigma^2/n_b: sigma^2 ~ M2/(B-1), and the mean's variance is sigma^2 / sum n_b.
        const double k = 1.0 / (a.w * double(a.n - 1));
        s.var_of_mean = {a.m2[0] * k, a.m2[1] * k, a.m2[2] * k};
    }
    return s;
}

ErrorEstimate Film::estimate_error(double eps) const {
    std::vector<ErrorPart> parts(error_parts());
    for (size_t c = 0; c < parts.size(); ++c) parts[c] = error_part(c, eps);
    return error_of(parts);
}

Film::ErrorPart Film::error_part(size_t chunk, double eps) const {
    ErrorPart e;
    const size_t end = std::min(px_.size(), (chunk + 1) * kErrorChunk);
    for (size_t i = chunk * kErrorChunk; i < end; ++i) {
        const Accum& a = px_[i];
        const double m = (a.mean[0] + a.mean[1] + a.mean[2]) / 3.0;
        e.mean += m;
        if (a.n < 2) {
            e.unknown = true;
            continue;
        }
        const double v = (a.m2[0] + a.m2[1] + a.m2[2]) / (3.0 * a.w * double(a.n - 1));
        e.var += v;
        e.rel += std::sqrt(v) / std::max(m, eps);
    }
    return e;
}

ErrorEstimate Film::error_of(std::span<const ErrorPart> parts) const {
    ErrorEstimate e;
    if (px_.empty()) return e;
    double sum_rel = 0, sum_mean = 0, sum_var = 0;
    bool unknown = false;
    for (const ErrorPart& p : parts) {
        sum_rel += p.rel;
        sum_mean += p.mean;
        sum_var += p.var;
        unknown = unknown || p.unknown;
    }
    const double N = double(px_.size());
    e.image_mean = sum_mean / N;
    if (unknown) {
        e.mean_rel_error = e.image_mean_stderr = std::numeric_limits<double>::infinity();
    } else {
        e.mean_rel_error = sum_rel / N;
        // Pixels are independent, so the variance of their mean is sum(var) / N^2.
        e.image_mean_stderr = std::sqrt(sum_var) / N;
    }
    return e;
}

void Film::clear() { std::fill(px_.begin(), px_.end(), Accum{}); }

PixelState Film::state(int x, int y) const {
    const Accum& a = px_[index(x, y)];
    PixelState s;
    s.n = a.n;
    s.w = a.w;
    for (int c = 0; c < 3; ++c) {
        s.mean[c] = a.mean[c];
        s.m2[c] = a.m2[c];
    }
    return s;
}

namespace {

// Empty string: a state some film could hold; otherwise why not.
const char* invalid_state(const PixelState& s) {
    if (!std::isfinite(s.w) || s.w < 0 || (s.n == 0) != (s.w == 0)) return "bad sample weight";
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(s.mean[k]) || !std::isfinite(s.m2[k]) || s.m2[k] < 0)
            return "non-finite or negative statistics";
    if (s.n == 0)
        for (int k = 0; k < 3; ++k)
            if (s.mean[k] != 0 || s.m2[k] != 0) return "statistics for an empty pixel";
    return "";
}

}  // namespace

void Film::set_state(int x, int y, const PixelState& s) {
    Accum& a = px_[index(x, y)];
    if (const char* why = invalid_state(s); *why)
        throw std::runtime_error("pixel (" + std::to_string(x) + ", " + std::to_string(y) + "): " + why);
    a.n = s.n;
    a.w = s.w;
    for (int c = 0; c < 3; ++c) {
        a.mean[c] = s.mean[c];
        a.m2[c] = s.m2[c];
    }
}

void Film::merge(const Film& other) {
    if (other.desc_.width != desc_.width || other.desc_.height != desc_.height || other.crop_.x0 != crop_.x0 ||
        other.crop_.y0 != crop_.y0 || other.crop_.x1 != crop_.x1 || other.crop_.y1 != crop_.y1)
        throw std::invalid_argument("Film::merge: films differ in size or crop");
    for (size_t i = 0; i < px_.size(); ++i) {
        Accum& a = px_[i];
        const Accum& b = other.px_[i];
        if (b.n == 0) continue;
        if (a.n == 0) {
            a = b;
            continue;
        }
        const double wa = a.w, wb = b.w, w = wa + wb;
        for (int c = 0; c < 3; ++c) {
            const double delta = b.mean[c] - a.mean[c];
            a.mean[c] += delta * (wb / w);
            a.m2[c] += b.m2[c] + delta * delta * (wa * wb / w);
        }
        a.n += b.n;
        a.w = w;
    }
}

// ---- Serialization ------------------------------------------------------------------------
//
// Layout, all little-endian:
//   char[8] "OMGFILM\0" | u32 version | i32 width, height, crop x0, y0, x1, y1 | u64 pixel count
//   pixel count x { u64 n | f64 weight | f64 mean[3] | f64 m2[3] }   (crop, row-major)
//   u64 checksum of every byte before it (FNV-1a over little-endian 64-bit words, then the
//   remaining bytes: word-at-a-time keeps a 1024^2 checkpoint fast)
// The checksum catches torn or bit-flipped checkpoints that size checks alone would load.

namespace {

constexpr char kMagic[8] = {'O', 'M', 'G', 'F', 'I', 'L', 'M', '\0'};
constexpr uint32_t kVersion = 2;  // 2: per-pixel weight sum (batch means)
constexpr size_t kHeaderBytes = 8 + 4 + 6 * 4 + 8;
constexpr size_t kPixelBytes = 8 + 7 * 8;

uint64_t load_le64(const uint8_t* p) {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= uint64_t(p[i]) << (8 * i);  // compilers fuse this to one load
    return v;
}

uint64_t checksum(const uint8_t* p, size_t n) {
    uint64_t h = 0xcbf29ce484222325ULL;
    size_t i = 0;
    for (; i + 8 <= n; i += 8) {
        h ^= load_le64(p + i);
        h *= 0x100000001b3ULL;
        h ^= h >> 29;  // a 64-bit word needs more mixing than FNV's byte step gives
    }
    for (; i < n; ++i) {
        h ^= p[i];
        h *= 0x100000001b3ULL;
    }
    return h;
}

struct Writer {
    uint8_t* p;
    void u64(uint64_t v) {
        for (int i = 0; i < 8; ++i) p[i] = uint8_t(v >> (8 * i));
        p += 8;
    }
    void u32(uint32_t v) {
        for (int i = 0; i < 4; ++i) p[i] = uint8_t(v >> (8 * i));
        p += 4;
    }
    void f64(double v) { u64(std::bit_cast<uint64_t>(v)); }
};

struct Reader {
    const uint8_t* p;
    uint64_t u64() {
        const uint64_t v = load_le64(p);
        p += 8;
        return v;
    }
    uint32_t u32() {
        uint32_t v = 0;
        for (int i = 0; i < 4; ++i) v |= uint32_t(p[i]) << (8 * i);
        p += 4;
        return v;
    }
    int32_t i32() { return int32_t(u32()); }
    double f64() { return std::bit_cast<double>(u64()); }
};

[[noreturn]] void corrupt(const std::string& why) { throw std::runtime_error("film checkpoint: " + why); }

}  // namespace

std::vector<uint8_t> Film::serialize() const {
    std::vector<uint8_t> out(kHeaderBytes + px_.size() * kPixelBytes + 8);
    std::memcpy(out.data(), kMagic, 8);
    Writer w{out.data() + 8};
    w.u32(kVersion);
    for (int v : {desc_.width, desc_.height, crop_.x0, crop_.y0, crop_.x1, crop_.y1}) w.u32(uint32_t(v));
    w.u64(px_.size());
    for (const Accum& a : px_) {
        w.u64(a.n);
        w.f64(a.w);
        for (double v : a.mean) w.f64(v);
        for (double v : a.m2) w.f64(v);
    }
    w.u64(checksum(out.data(), out.size() - 8));
    return out;
}

Film Film::deserialize(const FilmDesc& desc, std::span<const uint8_t> bytes) {
    Film film(desc);
    if (bytes.size() < kHeaderBytes + 8) corrupt("truncated header (" + std::to_string(bytes.size()) + " bytes)");
    if (std::memcmp(bytes.data(), kMagic, 8) != 0) corrupt("bad magic");
    Reader r{bytes.data() + 8};
    const uint32_t version = r.u32();
    if (version != kVersion) corrupt("unsupported version " + std::to_string(version));
    const int w = r.i32(), h = r.i32(), x0 = r.i32(), y0 = r.i32(), x1 = r.i32(), y1 = r.i32();
    const uint64_t count = r.u64();
    // Check the count against the actual size before trusting it in any arithmetic.
    if (count > (bytes.size() - kHeaderBytes - 8) / kPixelBytes ||
        bytes.size() != kHeaderBytes + count * kPixelBytes + 8)
        corrupt("size " + std::to_string(bytes.size()) + " does not match pixel count " + std::to_string(count));
    Reader tail{bytes.data() + bytes.size() - 8};
    if (tail.u64() != checksum(bytes.data(), bytes.size() - 8)) corrupt("checksum mismatch");
    const Rect c = film.crop_;
    if (w != desc.width || h != desc.height || x0 != c.x0 || y0 != c.y0 || x1 != c.x1 || y1 != c.y1 ||
        count != film.px_.size())
        corrupt("written for a film of another size or crop");
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            PixelState st;
            st.n = r.u64();
            st.w = r.f64();
            for (double& v : st.mean) v = r.f64();
            for (double& v : st.m2) v = r.f64();
            try {
                film.set_state(x, y, st);
            } catch (const std::runtime_error& e) {
                corrupt(e.what());
            }
        }
    return film;
}

}  // namespace omega
