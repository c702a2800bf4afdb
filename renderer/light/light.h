#pragma once
// The closed set of emitters, dispatched through std::variant.
// Densities: pdf_sa is per unit solid angle at the receiving point; delta lights (point, spot,
// directional) have none and report delta = true with a discrete probability of 1.
#include <memory>
#include <optional>
#include <variant>

#include "light/envmap.h"
#include "math/frame.h"
#include "math/vec.h"

namespace omega {

class Scene;
struct SurfaceHit;

struct AreaLight {
    uint32_t shape = 0;
    Rgb radiance;
    bool two_sided = false;
};
struct PointLight {
    Vec3 position;
    Rgb intensity;  // W/sr
};
// Mitsuba's spot: full intensity inside beam_width, falling off linearly in angle to 0 at cutoff.
struct SpotLight {
    Vec3 position;
    Frame frame;  // frame.n is the axis
    Rgb intensity;
    float cutoff_rad = 0, beam_rad = 0, cos_cutoff = 1;
};
struct DirectionalLight {
    Vec3 direction;  // of travel, unit
    Rgb irradiance;  // W/m^2
};
struct ConstantLight {
    Rgb radiance;
};
// An image-based environment (light/envmap.h); shared, so copying a Light stays cheap.
struct EnvMapLight {
    std::shared_ptr<const EnvMap> map;
};

using Light = std::variant<AreaLight, PointLight, SpotLight, DirectionalLight, ConstantLight, EnvMapLight>;

// A light sample seen from a reference point, for next-event estimation.
// Each three-float field starts a 16-byte slot: the samplers fill the struct with 16-byte
// stores, and packed fields straddled them, so a caller's 8-byte load of wi.x, wi.y (and of
// p_error's) missed store forwarding.
struct LightSample {
    alignas(16) Vec3 wi;  // unit, from the reference point towards the light
    float pdf_sa = 0;     // solid angle at the reference point (1 for delta lights)
    alignas(16) Vec3 p;   // point on the light (unused when infinite)
    bool delta = false;
    bool infinite = false;
    alignas(16) Rgb Li;   // radiance (or intensity / r^2 for point lights) arriving along -wi
    alignas(16) Vec3 p_error;  // error bound of p
    alignas(16) Vec3 n;        // its normal (zero for point-like lights)
};

std::optional<LightSample> light_sample_li(const Scene& scene, const Light& light, const Vec3& ref_p, Vec2 u);
// True where light_sample_li(scene, light, ref_p, u) fails for every u because ref_p lies behind
// a one-sided flat area light (light/emitter_plane.h): next-event estimation can skip it there.
bool light_faces_away(const Scene& scene, const Light& light, const Vec3& ref_p);
// Density (solid angle at ref_p) with which light_sample_li would pick the point `hit` on an area light.
float light_pdf_li_sa(const Scene& scene, const AreaLight& light, const Vec3& ref_p, const SurfaceHit& hit);
// Constant environment: density of direction wi.
inline float environment_pdf_li_sa() { return 0.07957747154594766788f; }  // 1 / 4pi, uniform sphere
// An environment (constant or envmap) seen along unit direction d (pointing away from the scene):
// the radiance arriving from d, and the solid-angle density with which light_sample_li picks d.
// Both are zero for any other light.
Rgb environment_le(const Light& light, const Vec3& d);
float environment_pdf_li_sa(const Light& light, const Vec3& d);
bool is_environment(const Light& light);
// Radiance leaving an area light at `hit` towards w.
Rgb area_light_le(const AreaLight& light, const SurfaceHit& hit, const Vec3& w);
// What a finite light's endpoint at `at` sends along unit direction w: radiance x |cos| for area
// lights (per unit area and solid angle), intensity for point and spot lights.
Rgb light_emission_towards(const Light& light, const SurfaceHit& at, const Vec3& w);
// Emitted power, for choosing lights in proportion to it.
double light_power(const Scene& scene, const Light& light);
bool light_is_delta(const Light& light);

}  // namespace omega
