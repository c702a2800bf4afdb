#include "texture/bitmap_texture.h"

#include <cmath>

namespace omega {

int wrap_index(long long i, int n, TexWrap wrap) {
    switch (wrap) {
        case TexWrap::Repeat: {
            long long r = i % n;
            return int(r < 0 ? r + n : r);
        }
        case TexWrap::Clamp: return int(std::clamp<long long>(i, 0, n - 1));
        case TexWrap::Mirror: {
            long long p = i % (2LL * n);
            if (p < 0) p += 2LL * n;
            return int(p < n ? p : 2LL * n - 1 - p);
        }
    }
    return 0;
}

namespace {

// floor(x) as an integer that cannot overflow (|uv| beyond 1e15 texels has no meaning anyway).
long long floor_index(float x, float& frac) {
    double f = std::floor(double(x));
    frac = float(double(x) - f);
    return (long long)std::clamp(f, -1e15, 1e15);
}

}  // namespace

Rgb BitmapTexture::eval(Vec2 uv_in) const {
    Vec2 uv = to_uv.apply(uv_in);
    // A NaN uv (degenerate geometry) must not become an out-of-range index.
    if (!std::isfinite(uv.x)) uv.x = 0;
    if (!std::isfinite(uv.y)) uv.y = 0;
    if (checker) {
        bool mu = uv.x - std::floor(uv.x) > 0.5f, mv = uv.y - std::floor(uv.y) > 0.5f;
        return mu == mv ? color0 : color1;
    }
    const Image& img = *image;
    const float x = uv.x * float(img.width), y = uv.y * float(img.height);
    float fx, fy;
    if (filter == TexFilter::Nearest) {
        long long i = floor_index(x, fx), j = floor_index(y, fy);
        return img.at(wrap_index(i, img.width, wrap), wrap_index(j, img.height, wrap));
    }
    long long i = floor_index(x - 0.5f, fx), j = floor_index(y - 0.5f, fy);
    int x0 = wrap_index(i, img.width, wrap), x1 = wrap_index(i + 1, img.width, wrap);
    int y0 = wrap_index(j, img.height, wrap), y1 = wrap_index(j + 1, img.height, wrap);
    Rgb top = img.at(x0, y0) * (1 - fx) + img.at(x1, y0) * fx;
    Rgb bottom = img.at(x0, y1) * (1 - fx) + img.at(x1, y1) * fx;
    return top * (1 - fy) + bottom * fy;
}

// The gradient of the bilinear interpolant of the first channel (Mitsuba 3's eval_1_grad), also
// for a nearest-filtered bitmap, whose own gradient is zero almost everywhere and would make a
// bump map do nothing. A checkerboard is piecewise constant: zero.
Vec2 BitmapTexture::eval_grad(Vec2 uv_in) const {
    if (checker) return {0.f, 0.f};
    Vec2 uv = to_uv.apply(uv_in);
    if (!std::isfinite(uv.x) || !std::isfinite(uv.y)) return {0.f, 0.f};
    const Image& img = *image;
    float fx, fy;
    long long i = floor_index(uv.x * float(img.width) - 0.5f, fx), j = floor_index(uv.y * float(img.height) - 0.5f, fy);
    int x0 = wrap_index(i, img.width, wrap), x1 = wrap_index(i + 1, img.width, wrap);
    int y0 = wrap_index(j, img.height, wrap), y1 = wrap_index(j + 1, img.height, wrap);
    float f00 = img.at(x0, y0).x, f10 = img.at(x1, y0).x, f01 = img.at(x0, y1).x, f11 = img.at(x1, y1).x;
    // d/du' and d/dv' in units of the transformed uv (texel steps times the resolution) ...
    float gu = ((f10 - f00) * (1 - fy) + (f11 - f01) * fy) * float(img.width);
    float gv = ((f01 - f00) * (1 - fx) + (f11 - f10) * fx) * float(img.height);
    // ... then through to_uv's linear part to surface uv (chain rule: d/du = a d/du' + d d/dv').
    const auto& m = to_uv.m;
    return {m[0] * gu + m[3] * gv, m[1] * gu + m[4] * gv};
}

Rgb BitmapTexture::mean() const {
    if (checker) return (color0 + color1) * 0.5f;  // equal areas over any whole number of checks
    Vec3d sum(0.0);
    for (const Rgb& t : image->texels) sum += Vec3d(t);
    return Rgb(sum / double(std::max<size_t>(image->texels.size(), 1)));
}

}  // namespace omega
