#pragma once
// Per-model entry points behind the std::variant dispatch in bsdf.cpp.
#include "bsdf/bsdf.h"

namespace omega {

Rgb eval(const DiffuseBsdf& b, const Vec3& wo, const Vec3& wi);
float pdf_sa(const DiffuseBsdf& b, const Vec3& wo, const Vec3& wi);
std::optional<BsdfSample> sample(const DiffuseBsdf& b, const Vec3& wo, Vec2 u);

Rgb eval(const ConductorBsdf& b, const Vec3& wo, const Vec3& wi);
float pdf_sa(const ConductorBsdf& b, const Vec3& wo, const Vec3& wi);
std::optional<BsdfSample> sample(const ConductorBsdf& b, const Vec3& wo, Vec2 u);

Rgb eval(const DielectricBsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode);
float pdf_sa(const DielectricBsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode);
std::optional<BsdfSample> sample(const DielectricBsdf& b, const Vec3& wo, float uc, Vec2 u, TransportMode mode);

// Plastic is reciprocal (f(wo, wi) = f(wi, wo)) and has no refraction of its own, so the
// importance BSDF equals the radiance one and no TransportMode is needed.
Rgb eval(const PlasticBsdf& b, const Vec3& wo, const Vec3& wi);
float pdf_sa(const PlasticBsdf& b, const Vec3& wo, const Vec3& wi);
std::optional<BsdfSample> sample(const PlasticBsdf& b, const Vec3& wo, float uc, Vec2 u);

// Thin sheet: only delta lobes (eval and pdf_sa are 0 everywhere); reciprocal and without
// refraction, so the importance BSDF equals the radiance one.
std::optional<BsdfSample> sample(const ThinDielectricBsdf& b, const Vec3& wo, float uc);

}  // namespace omega
