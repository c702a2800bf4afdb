#include "bsdf/models.h"
#include "sampling/warp.h"

namespace omega {

namespace {
// Two-sided surfaces behave as if seen from wo's side (Mitsuba's twosided): flip both directions.
bool orient(const DiffuseBsdf& b, Vec3& wo, Vec3& wi) {
    if (wo.z < 0 && b.two_sided) {
        wo = -wo;
        wi = -wi;
    }
    return wo.z > 0 && wi.z > 0;
}
}  // namespace

Rgb eval(const DiffuseBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (!orient(b, wo, wi)) return Rgb(0.f);
    return b.reflectance * kInvPi;
}

float pdf_sa(const DiffuseBsdf& b, const Vec3& wo_in, const Vec3& wi_in) {
    Vec3 wo = wo_in, wi = wi_in;
    if (!orient(b, wo, wi)) return 0.f;
    return cosine_hemisphere_pdf_sa(wi);
}

std::optional<BsdfSample> sample(const DiffuseBsdf& b, const Vec3& wo, Vec2 u) {
    if (wo.z == 0 || (wo.z < 0 && !b.two_sided)) return std::nullopt;
    Vec3 wi = square_to_cosine_hemisphere(u);
    BsdfSample s;
    s.pdf_sa = cosine_hemisphere_pdf_sa(wi);
    if (!(s.pdf_sa > 0)) return std::nullopt;
    s.wi = wo.z < 0 ? -wi : wi;
    s.weight = b.reflectance;  // f cos / pdf = (R/pi) cos / (cos/pi)
    s.lobe = kLobeReflection | kLobeDiffuse;
    return s;
}

}  // namespace omega
