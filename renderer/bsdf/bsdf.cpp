#include "bsdf/bsdf.h"

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
// A copy of model m with the textured parameter `value` looked up at uv and the texture dropped.
template <class T>
const Bsdf& looked_up(const T& m, Rgb T::*value, const BitmapTexture* T::*tex, Vec2 uv, Bsdf& tmp) {
    T q = m;
    q.*value = (q.*tex)->eval(uv);
    q.*tex = nullptr;
    tmp = q;
    return tmp;
}
}  // namespace

const Bsdf& resolve_textured(const Bsdf& b, Vec2 uv, Bsdf& tmp) {
    if (const auto* p = std::get_if<PlasticBsdf>(&b))
        return looked_up(*p, &PlasticBsdf::diffuse_reflectance, &PlasticBsdf::diffuse_reflectance_tex, uv, tmp);
    if (const auto* c = std::get_if<ConductorBsdf>(&b))
        return looked_up(*c, &ConductorBsdf::specular_reflectance, &ConductorBsdf::specular_reflectance_tex, uv, tmp);
    return looked_up(std::get<DiffuseBsdf>(b), &DiffuseBsdf::reflectance, &DiffuseBsdf::reflectance_tex, uv, tmp);
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
