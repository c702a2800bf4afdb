#pragma once
// Warps from the unit square to common domains. Each pdf names its measure:
// *_pdf_sa is per unit solid angle, *_pdf_area per unit area.
#include "math/vec.h"

namespace omega {

// {cos x, sin x} for |x| <= pi/4, within an ulp or two of libm's (warp_test checks it).
Vec2 sincos_quarter_pi(float x);
Vec2 square_to_uniform_disk_concentric(Vec2 u);
inline float square_to_uniform_disk_pdf_area() { return kInvPi; }

Vec3 square_to_cosine_hemisphere(Vec2 u);
inline float cosine_hemisphere_pdf_sa(const Vec3& w) { return w.z > 0 ? w.z * kInvPi : 0.f; }

Vec3 square_to_uniform_sphere(Vec2 u);
inline float uniform_sphere_pdf_sa() { return kInv4Pi; }

Vec3 square_to_uniform_hemisphere(Vec2 u);
inline float uniform_hemisphere_pdf_sa(const Vec3& w) { return w.z > 0 ? kInv2Pi : 0.f; }

// Uniform over the cone of directions around +z with cos(theta) >= cos_max.
Vec3 square_to_uniform_cone(Vec2 u, float cos_max);
float uniform_cone_pdf_sa(const Vec3& w, float cos_max);

// Uniform barycentrics (b0, b1) over a triangle (Heitz 2019 low-distortion map).
Vec2 square_to_uniform_triangle(Vec2 u);

// Tent of radius 1 on [-1, 1]: density 1 - |x|.
float sample_tent(float u);
inline float tent_pdf(float x) { return std::abs(x) >= 1 ? 0.f : 1.f - std::abs(x); }


}  // namespace omega
