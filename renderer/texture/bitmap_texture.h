#pragma once
// A bitmap texture as Mitsuba 3 defines it: uv (0, 0) is the first texel of the first stored row
// (the image's top-left corner), u runs along a row and v down the rows; texel (i, j) covers
// [i/w, (i+1)/w] x [j/h, (j+1)/h]. Bilinear interpolation weighs the four nearest texel centres.
//
// The same struct also holds Mitsuba's procedural `checkerboard` (checker = true, no image):
// every textured parameter then takes either kind through one pointer type.
//
// Built once with the Scene, then read-only: eval() is safe to call from every render thread.
#include <memory>

#include "texture/image.h"
#include "texture/texture_types.h"

namespace omega {

struct BitmapTexture {
    std::shared_ptr<const Image> image;  // shared by every texture that names the same file
    TexFilter filter = TexFilter::Bilinear;
    TexWrap wrap = TexWrap::Repeat;
    UvTransform to_uv;
    // Checkerboard (Mitsuba 3's checkerboard.cpp): with (u', v') = to_uv(uv), color0 where
    // frac(u') > 1/2 equals frac(v') > 1/2, color1 elsewhere: 2 x 2 checks per unit of uv'.
    bool checker = false;
    Rgb color0{0.4f, 0.4f, 0.4f}, color1{0.2f, 0.2f, 0.2f};  // Mitsuba's defaults

    // The reflectance at surface coordinates `uv` (to_uv is applied here).
    Rgb eval(Vec2 uv) const;
    // d(first channel)/du' and /dv' of the bilinear interpolant, in units of uv (for bump maps,
    // as Mitsuba's eval_1_grad), chained through to_uv back to surface uv.
    Vec2 eval_grad(Vec2 uv) const;
    // The average texel: stands in for the texture where no hit is at hand.
    Rgb mean() const;
};

// Index `i` folded into [0, n) by the wrap mode (Dr.Jit's rules, as Mitsuba 3 uses them).
int wrap_index(long long i, int n, TexWrap wrap);

}  // namespace omega
