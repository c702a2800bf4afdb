#pragma once
// Emission sampling for light subpaths (Veach 8.3.2): a light's emission splits into a spatial
// part L_e^(0) (a point on the light, density pdf_pos in area measure) and a directional part
// L_e^(1) (density pdf_dir in solid angle). Delta parts report a density of 1 and set the flag.
// Lights at infinity (directional, constant) start their rays on a disk of the scene's bounding
// radius facing the chosen direction; pdf_pos is then per unit area of that disk.
#include <optional>

#include "light/light.h"
#include "scene/ray.h"

namespace omega {

struct LightEmission {
    Ray ray;                // leaves the light (origin offset off area lights)
    SurfaceHit origin;      // the point on the light (area lights: with normal and error bound)
    Rgb Le;                 // radiance (area, constant), intensity (point, spot) or irradiance (directional) along ray
    double pdf_pos = 1;     // area density of the origin (1 for a delta position)
    double pdf_dir = 1;     // solid-angle density of the direction (1 for a delta direction)
    bool delta_pos = false, delta_dir = false;
    bool infinite = false;
};

std::optional<LightEmission> light_sample_le(const Scene& scene, const Light& light, Vec2 u_pos, Vec2 u_dir);

// Densities with which light_sample_le emits from `p` (normal n, for area lights) along `w`.
// For lights at infinity, w is the direction of travel and pdf_pos is per unit disk area.
void light_pdf_le(const Scene& scene, const Light& light, const Vec3& n, const Vec3& w, double& pdf_pos,
                  double& pdf_dir);

// Density (solid angle) of light_sample_le choosing direction w for a light at infinity; used
// when a camera subpath escapes.
double infinite_light_pdf_dir(const Light& light, const Vec3& w);

}  // namespace omega
