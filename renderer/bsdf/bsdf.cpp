#include "bsdf/bsdf.h"

#include <algorithm>
#include <limits>
#include <type_traits>

#include "bsdf/models.h"
#include "texture/bitmap_texture.h"

namespace omega {

Rgb bsdf_eval(const Bsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode) {
    return std::visit(
        [&](const auto& m) -> Rgb {
            using T = std::decay_t<decltype(m)>;
            // Black and thin sheet: no non-delta lobe, hence no density and no value.
            if constexpr (std::is_same_v<T, BlackBsdf> || std::is_same_v<T, ThinDielectricBsdf>) return Rgb(0.f);
            else if constexpr (std::is_same_v<T, DielectricBsdf>) return eval(m, wo, wi, mode);
            else return eval(m, wo, wi);
        },
        b);
}

float bsdf_pdf_sa(const Bsdf& b, const Vec3& wo, const Vec3& wi, TransportMode mode) {
    return std::visit(
        [&](const auto& m) -> float {
            using T = std::decay_t<decltype(m)>;
            if constexpr (std::is_same_v<T, BlackBsdf> || std::is_same_v<T, ThinDielectricBsdf>) return 0.f;
            else if constexpr (std::is_same_v<T, DielectricBsdf>) return pdf_sa(m, wo, wi, mode);
            else return pdf_sa(m, wo, wi);
        },
        b);
}

std::optional<BsdfSample> bsdf_sample(const Bsdf& b, const Vec3& wo, float uc, Vec2 u, TransportMode mode) {
    return std::visit(
        [&](const auto& m) -> std::optional<BsdfSample> {
            using T = std::decay_t<decltype(m)>;
            if constexpr (std::is_same_v<T, BlackBsdf>) return std::nullopt;
            else if constexpr (std::is_same_v<T, DielectricBsdf>) return sample(m, wo, uc, u, mode);
            else if constexpr (std::is_same_v<T, PlasticBsdf>) return sample(m, wo, uc, u);
            else if constexpr (std::is_same_v<T, ThinDielectricBsdf>) return sample(m, wo, uc);
            else return sample(m, wo, u);
        },
        b);
}

namespace {
// Each textured parameter looked up at uv, its texture dropped (the copy is then untextured).
void look_up(Rgb& value, const BitmapTexture*& tex, Vec2 uv) {
    if (!tex) return;
    value = tex->eval(uv);
    tex = nullptr;
}
float scalar_alpha(const BitmapTexture& tex, Vec2 uv, float lo = kMinTexturedAlpha, float hi = 1.f) {
    return texel_alpha(tex.eval(uv), lo, hi);
}
void look_up_alpha(float& au, float& av, const BitmapTexture*& tex, Vec2 uv) {
    if (!tex) return;
    au = av = scalar_alpha(*tex, uv);
    tex = nullptr;
}

void look_up_all(DiffuseBsdf& m, Vec2 uv) {
    look_up(m.reflectance, m.reflectance_tex, uv);
    if (m.alpha_tex) {  // Oren-Nayar: any slope >= 0 (0 is Lambert), as the scene format allows
        m.alpha = scalar_alpha(*m.alpha_tex, uv, 0.f, std::numeric_limits<float>::infinity());
        m.alpha_tex = nullptr;
    }
}
void look_up_all(ConductorBsdf& m, Vec2 uv) {
    look_up(m.specular_reflectance, m.specular_reflectance_tex, uv);
    look_up_alpha(m.alpha_u, m.alpha_v, m.alpha_tex, uv);
}
void look_up_all(DielectricBsdf& m, Vec2 uv) {
    look_up(m.specular_reflectance, m.specular_reflectance_tex, uv);
    look_up(m.specular_transmittance, m.specular_transmittance_tex, uv);
    look_up_alpha(m.alpha_u, m.alpha_v, m.alpha_tex, uv);
}
void look_up_all(ThinDielectricBsdf& m, Vec2 uv) {
    look_up(m.specular_reflectance, m.specular_reflectance_tex, uv);
    look_up(m.specular_transmittance, m.specular_transmittance_tex, uv);
}
void look_up_all(PlasticBsdf& m, Vec2 uv) {
    look_up(m.diffuse_reflectance, m.diffuse_reflectance_tex, uv);
    look_up(m.specular_reflectance, m.specular_reflectance_tex, uv);
    if (m.alpha_tex) {
        m.alpha = scalar_alpha(*m.alpha_tex, uv);
        m.alpha_tex = nullptr;
    }
}
void look_up_all(BlackBsdf&, Vec2) {}
}  // namespace

const Bsdf& resolve_textured(const Bsdf& b, Vec2 uv, Bsdf& tmp) {
    tmp = b;
    std::visit([&](auto& m) { look_up_all(m, uv); }, tmp);
    return tmp;
}

uint8_t bsdf_lobes(const Bsdf& b) {
    return std::visit(
        [](const auto& m) -> uint8_t {
            using T = std::decay_t<decltype(m)>;
            if constexpr (std::is_same_v<T, BlackBsdf>) {
                return kLobeNone;
            } else if constexpr (std::is_same_v<T, DiffuseBsdf>) {
                return kLobeReflection | kLobeDiffuse;
            } else if constexpr (std::is_same_v<T, PlasticBsdf>) {
                // The coat's reflection and the substrate are separate lobes; a path through the
                // smooth coat's mirror lobe is S, one through the substrate or a rough coat is D.
                return kLobeReflection | kLobeDiffuse | (m.alpha == 0 ? kLobeDelta : kLobeGlossy);
            } else if constexpr (std::is_same_v<T, ThinDielectricBsdf>) {
                return kLobeReflection | kLobeTransmission | kLobeDelta;
            } else if constexpr (std::is_same_v<T, ConductorBsdf>) {
                bool smooth = m.alpha_u == 0 && m.alpha_v == 0;
                return kLobeReflection | (smooth ? kLobeDelta : kLobeGlossy);
            } else {
                bool smooth = m.alpha_u == 0 && m.alpha_v == 0;
                return kLobeReflection | kLobeTransmission | (smooth ? kLobeDelta : kLobeGlossy);
            }
        },
        b);
}

}  // namespace omega
