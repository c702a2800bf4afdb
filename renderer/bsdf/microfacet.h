#pragma once
// Anisotropic GGX and Beckmann microfacet distributions with the Smith masking model and
// sampling of the distribution of visible normals (VNDF). Microfacet normals m always have m.z > 0;
// callers flip directions below the surface before asking for G1/VNDF.
#include "bsdf/bsdf.h"
#include "math/vec.h"

namespace omega {

struct Microfacet {
    MicrofacetType type = MicrofacetType::GGX;
    float alpha_u = 0.1f, alpha_v = 0.1f;

    Microfacet() = default;
    // Clamped away from 0 so that nearly smooth surfaces stay finite.
    Microfacet(MicrofacetType t, float au, float av);

    // Normal distribution of m, normalised so that the projected area integrates to 1: ∫ D(m) m.z dm = 1.
    float D(const Vec3& m) const;
    // Smith Lambda; depends only on the direction's slope, symmetric under w -> -w.
    float lambda(const Vec3& w) const;
    // Masking of w by microfacet m: 0 for back-facing configurations.
    float G1(const Vec3& w, const Vec3& m) const;
    // Height-correlated masking-shadowing.
    float G(const Vec3& wo, const Vec3& wi, const Vec3& m) const;
    // Density of visible normals seen from wo (wo.z > 0), per solid angle of m.
    float pdf_visible_sa(const Vec3& wo, const Vec3& m) const;
    // Samples m ~ pdf_visible_sa(wo, .) for wo.z > 0.
    Vec3 sample_visible(const Vec3& wo, Vec2 u) const;
};

// Exposed for tests.
double erfinv(double y);

}  // namespace omega
