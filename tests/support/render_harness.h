#pragma once
// Shared by integration tests: build scenes in code, render them, and compare results
// statistically (z-tests against the estimated standard error, never fixed tolerances).
#include <functional>
#include <memory>
#include <string>

#include "film/film.h"
#include "integrator/render_session.h"
#include "scene/scene.h"
#include "scene/scene_desc.h"

namespace omega::test {

struct RenderResult {
    std::unique_ptr<Scene> scene;
    std::unique_ptr<RenderSession> session;
    PassReport report;
    const Film& film() const { return session->film(); }
};

RenderResult render(const SceneDesc& desc, long long spp, uint64_t seed = 0, int threads = 0, int tile_size = 32);
// The same with the path-class breakdown on (integrator/breakdown.h); its report is breakdown().
RenderResult render_breakdown(const SceneDesc& desc, long long spp, const BreakdownDesc& bd, uint64_t seed = 0,
                              int threads = 0, int tile_size = 32);
// The breakdown report of a render_breakdown result.
BreakdownReport breakdown(const RenderResult& r);
// One breakdown row by kind and name ("class", "L D E"; "length", "k=2"); null if absent.
const BreakdownRow* breakdown_row(const BreakdownReport& r, const std::string& kind, const std::string& name);

// Whether two films hold the same accumulator state, bit for bit: per pixel the count, the weight,
// the mean and M2 (Film::state), so equal images with different variance also differ.
bool same_bits(const Film& a, const Film& b);

// A minimal valid scene: a perspective camera at the origin looking along +z, film w x h, box filter.
SceneDesc empty_scene(int w, int h);
MaterialDesc diffuse(const std::string& name, Rgb reflectance);
// A rough metal cube on a diffuse floor lit by a small spherical emitter, seen from above: every
// integrator reaches it, with glossy and diffuse paths (determinism and merge tests).
SceneDesc metal_cube_scene(int w, int h);
// A glass ball focusing a spherical light (radius lamp_radius, radiance lamp_radiance) onto a
// diffuse floor, seen from above without the ball (a path ending S E cannot be light traced):
// caustics, direct and indirect light. 24 x 24, max_depth 6.
SceneDesc glass_caustic_scene(double lamp_radius, float lamp_radiance);

struct ZStats {
    double z = 0;        // aggregate z of the mean difference
    double max_abs_z = 0;  // largest per-block |z|
    int blocks = 0;
};

// Mean over the crop of channel-averaged pixel means minus `expected(x, y)` (the expected
// channel-averaged pixel value), as one z-score using the films' variance estimates.
ZStats z_against(const Film& film, const std::function<double(int, int)>& expected);
// Independent renders a and b: per-block z-scores (block x block pixels) of the difference.
ZStats z_between(const Film& a, const Film& b, int block);

// |z| bound with family-wise false-alarm rate alpha over n tests (Bonferroni, two-sided).
double z_threshold(int n, double alpha = 1e-3);

}  // namespace omega::test
