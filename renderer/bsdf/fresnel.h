#pragma once
// Fresnel reflectance for dielectric and conductor interfaces (unpolarised light).
#include "math/vec.h"

namespace omega {

struct DielectricFresnel {
    float r = 1;           // reflectance
    float cos_t = 0;       // signed cosine of the transmitted direction (opposite sign to cos_i)
    float eta_it = 1;      // IOR ratio transmitted side / incident side
    float eta_ti = 1;      // its inverse
};

// cos_i is signed against the interface normal; cos_i < 0 means arriving from the inside, so the
// ratio flips. eta = int_ior / ext_ior. Total internal reflection gives r = 1, cos_t = 0.
DielectricFresnel fresnel_dielectric(float cos_i, float eta);

// Conductor with complex IOR eta + i k, evaluated per RGB channel; cos_i is taken by magnitude.
Rgb fresnel_conductor(float cos_i, const Rgb& eta, const Rgb& k);
float fresnel_conductor(float cos_i, float eta, float k);

// Refracts w about m given the Fresnel result for dot(w, m); both point away from the surface.
inline Vec3 refract_dir(const Vec3& w, const Vec3& m, float cos_i, const DielectricFresnel& f) {
    return m * (cos_i * f.eta_ti + f.cos_t) - w * f.eta_ti;
}
inline Vec3 reflect_dir(const Vec3& w, const Vec3& m) { return m * (2.f * dot(w, m)) - w; }

}  // namespace omega
