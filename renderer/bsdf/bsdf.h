#pragma once
// The closed set of BSDFs, dispatched through std::variant (no virtual calls in the inner loop).
//
// Conventions (shared by every model and every caller):
// - Directions are in the local shading frame (z = shading normal), both pointing away from the
//   surface: wo towards the previous vertex (the camera side for radiance), wi towards the next.
// - eval() returns f(wo, wi) WITHOUT the cosine factor.
// - pdf_sa() is per unit solid angle around wi. Delta components have no density: eval() and
//   pdf_sa() return 0 for them and only sample() can produce them.
// - sample() returns weight = f * |cos(wi)| / pdf_sa for non-delta lobes; for a delta lobe it is the
//   discrete weight (e.g. F / P(choose reflection)) and pdf_sa holds the discrete probability.
// - TransportMode::Importance is used when tracing from lights (the adjoint BSDF); it drops the
//   1/eta^2 radiance scaling at refraction.
#include <cstdint>
#include <optional>
#include <variant>

#include "math/frame.h"
#include "math/vec.h"

namespace omega {

enum class TransportMode : uint8_t { Radiance, Importance };

enum class MicrofacetType : uint8_t { GGX, Beckmann };

// Lobe flags, also used by the full-path classifier (S = delta, D = everything else).
enum LobeFlags : uint8_t {
    kLobeNone = 0,
    kLobeReflection = 1 << 0,
    kLobeTransmission = 1 << 1,
    kLobeDiffuse = 1 << 2,
    kLobeGlossy = 1 << 3,
    kLobeDelta = 1 << 4,
};

// wi comes first, each three-float field followed by a float: the samplers' stores of a field
// then cover the callers' 8-byte loads of its x and y. With weight first, wi.x shared a 16-byte
// store with weight and wi.y the next one, so every bounce's read of wi.x, wi.y missed store
// forwarding (perf: the hottest load of the path tracer and the subpath walk).
struct BsdfSample {
    Vec3 wi;                // local frame
    float pdf_sa = 0;       // solid angle density, or the discrete probability for a delta lobe
    Rgb weight;             // f |cos wi| / pdf, or the discrete weight for a delta lobe
    float eta = 1;          // relative IOR along the sampled direction (1 for reflection)
    uint8_t lobe = kLobeNone;
    bool is_delta() const { return lobe & kLobeDelta; }
};

struct BitmapTexture;  // texture/bitmap_texture.h

// Lambertian (alpha == 0) or Oren-Nayar rough diffuse (alpha > 0: Mitsuba 0.6's `roughdiffuse`,
// see diffuse.cpp). Both are reciprocal and cosine-sampled, so the importance BSDF is the
// radiance one and the density is the same: alpha changes only eval() and the sample weight.
struct DiffuseBsdf {
    // With a texture: its mean, for the few uses that have no hit at hand (none in rendering).
    Rgb reflectance{0.5f, 0.5f, 0.5f};
    bool two_sided = true;
    // Owned by the Scene; looked up per hit by resolve_bsdf(). Null in a SceneDesc (the
    // description names the file in MaterialDesc::reflectance_texture instead).
    const BitmapTexture* reflectance_tex = nullptr;
    // Beckmann-style RMS slope of the micro-geometry (Mitsuba's alpha; sigma = alpha / sqrt 2).
    float alpha = 0;
    // Mitsuba's useFastApprox: the qualitative model's A + B form without interreflection.
    bool fast_approx = false;
    // A roughness texture for alpha (see resolve_textured: a scalar per hit).
    const BitmapTexture* alpha_tex = nullptr;
};

// Conductor: alpha == 0 is a smooth mirror. Without eta/k (has_ior false) Fresnel is 1.
struct ConductorBsdf {
    Rgb eta{0.f, 0.f, 0.f}, k{1.f, 1.f, 1.f};
    bool has_ior = false;
    Rgb specular_reflectance{1.f, 1.f, 1.f};
    float alpha_u = 0, alpha_v = 0;
    MicrofacetType distribution = MicrofacetType::GGX;
    bool two_sided = true;
    // As DiffuseBsdf::reflectance_tex, for specular_reflectance (which then holds the mean).
    const BitmapTexture* specular_reflectance_tex = nullptr;
    // Isotropic roughness per hit: alpha_u = alpha_v = the texture's scalar (resolve_textured).
    const BitmapTexture* alpha_tex = nullptr;
};

// Dielectric interface; eta = int_ior / ext_ior. alpha == 0 is smooth.
struct DielectricBsdf {
    float eta = 1.5f;
    Rgb specular_reflectance{1.f, 1.f, 1.f};
    Rgb specular_transmittance{1.f, 1.f, 1.f};
    float alpha_u = 0, alpha_v = 0;
    MicrofacetType distribution = MicrofacetType::GGX;
    // As ConductorBsdf's textures.
    const BitmapTexture* specular_reflectance_tex = nullptr;
    const BitmapTexture* specular_transmittance_tex = nullptr;
    const BitmapTexture* alpha_tex = nullptr;
};

// Thin dielectric sheet (a window pane): an infinitely thin slab of relative IOR eta = int_ior /
// ext_ior with both faces parallel. Specular reflection plus straight-through transmission
// (wi = -wo, no refraction offset), the slab's internal bounces summed per polarisation as
// Tungsten's thinsheet does (see thin_dielectric.cpp). Both lobes are delta; the sheet is
// symmetric, so it looks the same from either side and needs no TransportMode.
struct ThinDielectricBsdf {
    float eta = 1.5f;
    Rgb specular_reflectance{1.f, 1.f, 1.f};
    Rgb specular_transmittance{1.f, 1.f, 1.f};
    const BitmapTexture* specular_reflectance_tex = nullptr;
    const BitmapTexture* specular_transmittance_tex = nullptr;
};

// Plastic: a smooth dielectric coat over a Lambertian base (Tungsten's plastic / rough_plastic,
// Mitsuba's plastic / roughplastic; see plastic.cpp for the model and where it comes from).
// alpha == 0 is the smooth coat (a delta reflection plus the diffuse substrate); alpha > 0 makes
// the coat's reflection a glossy microfacet lobe (isotropic, as in both reference renderers).
struct PlasticBsdf {
    // int_ior / ext_ior. Set it through set_eta(), which keeps fdr_int in step.
    float eta = 1.5f;
    // Hemispherical average internal reflectance of the coat, 2 ∫ F_int(mu) mu dmu, by quadrature
    // in set_eta() (once per material: the BSDF is evaluated millions of times, eta never
    // changes). The default belongs to eta = 1.5 (a test keeps it in step with plastic_fdr_int).
    float fdr_int = 0.59634576f;
    Rgb diffuse_reflectance{0.5f, 0.5f, 0.5f};
    Rgb specular_reflectance{1.f, 1.f, 1.f};
    // true: rho / (1 - rho fdr_int) (Tungsten; Mitsuba's nonlinear); false: rho / (1 - fdr_int)
    // (Mitsuba's default), which keeps the diffuse colour as given instead of saturating it.
    bool nonlinear = false;
    float alpha = 0;
    MicrofacetType distribution = MicrofacetType::Beckmann;
    bool two_sided = true;
    // As DiffuseBsdf::reflectance_tex, for diffuse_reflectance (which then holds the mean).
    const BitmapTexture* diffuse_reflectance_tex = nullptr;
    const BitmapTexture* specular_reflectance_tex = nullptr;
    const BitmapTexture* alpha_tex = nullptr;  // rough coat only

    void set_eta(float e);
};

// Absorbs everything; used for emitters that should not reflect.
struct BlackBsdf {};

using Bsdf = std::variant<DiffuseBsdf, ConductorBsdf, DielectricBsdf, PlasticBsdf, ThinDielectricBsdf, BlackBsdf>;

Rgb bsdf_eval(const Bsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode);
float bsdf_pdf_sa(const Bsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode);
std::optional<BsdfSample> bsdf_sample(const Bsdf& b, const Vec3& wo, float uc, Vec2 u, TransportMode mode);
// Union of the lobes this BSDF can ever produce (for classification and skipping work).
uint8_t bsdf_lobes(const Bsdf& b);
inline bool bsdf_is_delta_only(const Bsdf& b) {
    uint8_t l = bsdf_lobes(b);
    return l != kLobeNone && (l & (kLobeDiffuse | kLobeGlossy)) == 0;
}
inline bool bsdf_has_nondelta(const Bsdf& b) { return bsdf_lobes(b) & (kLobeDiffuse | kLobeGlossy); }
// Whether bsdf_sample() reads its 1D number `uc` (a choice between lobes): diffuse and
// conductor models have one lobe and ignore it.
inline bool bsdf_sample_uses_uc(const Bsdf& b) {
    return std::holds_alternative<DielectricBsdf>(b) || std::holds_alternative<PlasticBsdf>(b) ||
           std::holds_alternative<ThinDielectricBsdf>(b);
}

// Textured parameters, resolved at one surface point: the BSDF models never see a texture.
// Returns `b` itself when nothing in it is textured (no copy: the common case costs one test),
// otherwise `tmp`, filled with `b` whose textured parameters are looked up at `uv`.
// Every evaluation of a scene BSDF at a hit goes through this (path tracer, subpath walks,
// connections), so all integrators see the same textured albedo and roughness.
//
// A roughness texture gives a scalar per hit: the luminance (Rec. 709 weights) of its value,
// as Mitsuba 3's eval_1 takes it (0.6 took the channel average; the two agree on grey maps),
// clamped to [kMinTexturedAlpha, 1]: a texel of 0 would make a delta lobe of a surface the path
// classifier counts as glossy, and the microfacet densities are not defined there.
constexpr float kMinTexturedAlpha = 1e-3f;
// A roughness texel's scalar: luminance, within [lo, hi] (NaN becomes lo). Oren-Nayar's alpha
// takes [0, inf), the microfacet models' [kMinTexturedAlpha, 1].
inline float texel_alpha(Rgb v, float lo = kMinTexturedAlpha, float hi = 1.f) {
    const float lum = 0.212671f * v.x + 0.715160f * v.y + 0.072169f * v.z;
    return lum >= lo ? (lum < hi ? lum : hi) : lo;
}
const Bsdf& resolve_textured(const Bsdf& b, Vec2 uv, Bsdf& tmp);
namespace detail {
inline bool has_texture(const DiffuseBsdf& m) { return m.reflectance_tex || m.alpha_tex; }
inline bool has_texture(const ConductorBsdf& m) { return m.specular_reflectance_tex || m.alpha_tex; }
inline bool has_texture(const DielectricBsdf& m) {
    return m.specular_reflectance_tex || m.specular_transmittance_tex || m.alpha_tex;
}
inline bool has_texture(const ThinDielectricBsdf& m) { return m.specular_reflectance_tex || m.specular_transmittance_tex; }
inline bool has_texture(const PlasticBsdf& m) {
    return m.diffuse_reflectance_tex || m.specular_reflectance_tex || m.alpha_tex;
}
inline bool has_texture(const BlackBsdf&) { return false; }
}  // namespace detail
inline bool bsdf_is_textured(const Bsdf& b) {
    return std::visit([](const auto& m) { return detail::has_texture(m); }, b);
}
inline const Bsdf& resolve_bsdf(const Bsdf& b, Vec2 uv, Bsdf& tmp) {
    return bsdf_is_textured(b) ? resolve_textured(b, uv, tmp) : b;
}

// Hemispherical average of the dielectric Fresnel reflectance seen from inside a medium of
// relative index eta (int_ior / ext_ior): 2 ∫_0^1 F_int(mu) mu dmu, by quadrature in double.
float plastic_fdr_int(float eta);

// Reflectance of a thin slab of relative IOR eta at incidence |cos_i|, with the incoherent sum
// over the slab's internal bounces taken per polarisation and then averaged (Tungsten's
// Fresnel::thinFilmReflectance): R' = (2 Rs/(1 + Rs) + 2 Rp/(1 + Rp)) / 2. Its transmittance is
// 1 - R' (no absorption).
float thin_slab_reflectance(float cos_i, float eta);

}  // namespace omega
