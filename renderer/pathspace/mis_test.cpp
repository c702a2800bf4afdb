// For any sampled path, the MIS weights of all strategies that could produce it sum to 1, when
// each strategy computes its densities from its own split of the path. This checks the whole
// bookkeeping: pdf_fwd/pdf_rev from the random walks against the densities recomputed across
// each possible connecting edge, delta vertices, delta lights, pinhole and orthographic sensors.
#include <gtest/gtest.h>

#include <cmath>

#include "pathspace/connect.h"
#include "pathspace/mirror_connector.h"
#include "render_harness.h"

namespace omega {
namespace {

// Re-split the full path v_0..v_k at s: light prefix v_0..v_{s-1}, camera prefix v_k..v_s.
double weight_for_split(const Scene& scene, const std::vector<PathVertex>& v, int s, const StrategySet& set,
                        FullPathPdfs* out) {
    const int n = int(v.size());
    const int t = n - s;
    std::vector<PathVertex> light, camera;
    for (int i = 0; i < s; ++i) {
        PathVertex x = v[size_t(i)];
        if (i > 0) x.wo = v[size_t(i - 1)].infinite ? -v[size_t(i - 1)].dir : normalize(v[size_t(i - 1)].p() - x.p());
        light.push_back(x);
    }
    for (int i = n - 1; i >= s; --i) {
        PathVertex x = v[size_t(i)];
        if (i < n - 1) x.wo = normalize(v[size_t(i + 1)].p() - x.p());
        camera.push_back(x);
    }
    // Each subpath vertex keeps its side's densities: light side pdf_fwd = p_light.
    FullPathPdfs ref = *out;
    for (int i = 0; i < s; ++i) {
        light[size_t(i)].pdf_fwd = ref.p_light[size_t(i)];
        light[size_t(i)].pdf_rev = ref.p_sensor[size_t(i)];
    }
    for (int j = 0; j < t; ++j) {
        int i = n - 1 - j;
        camera[size_t(j)].pdf_fwd = ref.p_sensor[size_t(i)];
        camera[size_t(j)].pdf_rev = ref.p_light[size_t(i)];
    }
    // A split connecting at a vertex that scattered through a delta lobe cannot produce this path
    // (eval() has no delta part), even where the BSDF has other lobes to connect through (smooth
    // plastic): no table to compare.
    auto mixed_delta = [&](int i) {
        const PathVertex& x = v[size_t(i)];
        return i > 0 && i < n - 1 && x.delta && x.bsdf && bsdf_has_nondelta(*x.bsdf);
    };
    if (s >= 1 && t >= 1 && (mixed_delta(s - 1) || mixed_delta(s))) return -1.0;
    FullPathPdfs fp = full_path_pdfs(scene, light, camera, s, t, nullptr, nullptr, set.mirrors);
    *out = fp;
    if (!strategy_possible(fp, s) || !set.allows(s, t)) return 0.0;
    return mis_weight(fp, s, set);
}

struct Checked {
    int prefixed = 0;  // connections whose prefixed BDPT weight matched the table's
    int paths = 0;
    int connector_paths = 0;  // sampled by the planar-mirror connector
    int t0_paths = 0;  // sampled by t = 0
    int max_vertices = 0;
};

// BDPT without the connector weighs a connection from the subpaths' sums (mis_prefix.h): the
// same weight as the table's, to rounding, for every connection, and the same path (or none).
int check_prefixed_weight(const Scene& scene, const std::vector<PathVertex>& lit, const std::vector<PathVertex>& cam,
                          int s, int t, const Sampler& sampler, bool lens_hittable) {
    if (s + t < 3) return 0;
    StrategySet set{IntegratorType::Bdpt};
    set.lens_hittable = lens_hittable;
    TracerStats stats;
    ConnectStats table, prefixed;
    prefixed.prefix.prepare(scene, lit, cam);
    Sampler u1 = sampler, u2 = sampler;  // both draw the same endpoint samples (s = 1, t = 1)
    FullPathPdfs fp;
    auto a = connect(scene, lit, cam, s, t, set, u1, stats, table, nullptr, &fp);
    auto b = connect(scene, lit, cam, s, t, set, u2, stats, prefixed);
    EXPECT_EQ(a.has_value(), b.has_value()) << "s=" << s << " t=" << t;
    if (!a || !b) return 0;
    EXPECT_NEAR(b->weight, a->weight, 1e-12 + 1e-12 * a->weight) << "s=" << s << " t=" << t;
    EXPECT_EQ(table.bad_weights, prefixed.bad_weights);
    return 1;
}

// Samples subpath pairs, connects every strategy, and checks the weight sum for each full path.
Checked check_scene(const SceneDesc& desc, int samples, int max_depth) {
    auto scene = Scene::build(desc);
    Checked out;
    WalkLimits cam_lim{max_depth + 1, 1000}, light_lim{max_depth, 1000};
    TracerStats stats;
    ConnectStats cstats;
    const Sensor& sensor = scene->sensor();
    // Rectangles of smooth conductor are planar mirrors: the connector joins the strategies.
    const PlanarMirrors mirrors = find_planar_mirrors(*scene);
    const PlanarMirrors* mp = mirrors.empty() ? nullptr : &mirrors;
    for (int i = 0; i < samples; ++i) {
        Sampler rng(Rng::for_sample(99, 0, uint64_t(i)));  // independent: the checks need no layout
        Vec2 film{rng.next_1d() * float(sensor.width), rng.next_1d() * float(sensor.height)};
        Ray ray = sensor.generate_ray(film, {rng.next_1d(), rng.next_1d()});
        std::vector<PathVertex> cam, lit;
        std::vector<LensCrossing> lens;
        int nc = generate_camera_subpath(*scene, ray, cam_lim, rng, stats, cam);
        int nl = generate_light_subpath(*scene, light_lim, rng, stats, lit, &lens);
        // t = 0 strategies appear as s = -1 - (index of the lens crossing).
        for (int t = 0; t <= std::max(nc, 1); ++t)
            for (int s = (t == 0 ? -int(lens.size()) : 0); s <= (t == 0 ? -1 : std::max(nl, 1)); ++s) {
                const LensCrossing* lc = t == 0 ? &lens[size_t(-1 - s)] : nullptr;
                const int s_eff = lc ? lc->s + 1 : s;
                int k = s_eff + t - 1;
                if (k < 1 || k > max_depth) continue;
                if (!lc && ((t >= 2 && t > nc) || (s >= 2 && s > nl) || (t == 1 && s > nl))) continue;
                if (!lc && s == 0 && cam[size_t(t - 1)].light < 0) continue;
                if (!lc) out.prefixed += check_prefixed_weight(*scene, lit, cam, s, t, rng, sensor.lens_hittable());
                std::vector<PathVertex> full;
                FullPathPdfs fp;
                for (IntegratorType type : {IntegratorType::Bdpt, IntegratorType::Path, IntegratorType::Light})
                  // via = -1: strategy (s, t); via = i: the connector through mirror i (k = s + t).
                  for (int via = -1; via < (mp && !lc ? int(mp->list.size()) : 0); ++via) {
                    StrategySet set{type};
                    set.mirrors = mp;
                    set.lens_hittable = sensor.lens_hittable();
                    if (via < 0 ? !set.allows(s_eff, t) : !set.allows_connector(s, t) || s + t > max_depth) continue;
                    if (via >= 0 && s == 1 && t == 1 && nl < 1) continue;
                    std::optional<Connection> c;
                    if (lc) {
                        c = connect_lens(*scene, lit, *lc, set, cstats, &fp);
                        full.assign(lit.begin(), lit.begin() + lc->s);
                        full.push_back(lc->lens);
                    } else if (via >= 0) {
                        c = connect_via_mirror(*scene, via, lit, cam, s, t, set, rng, stats, cstats, &full, &fp);
                        if (c) ++out.connector_paths;
                    } else {
                        c = connect(*scene, lit, cam, s, t, set, rng, stats, cstats, &full, &fp);
                    }
                    if (!c) continue;
                    if (lc) ++out.t0_paths;
                    EXPECT_TRUE(std::isfinite(c->weight) && c->weight >= 0 && c->weight <= 1 + 1e-12);
                    double sum = 0;
                    // s2 = full.size() is t = 0: the light subpath reaching the lens.
                    for (int s2 = 0; s2 <= int(full.size()); ++s2) {
                        if (s2 == int(full.size()) && !fp.sensor_hittable) continue;  // no t = 0 table to compare
                        FullPathPdfs t2 = fp;
                        double w = weight_for_split(*scene, full, s2, set, &t2);
                        if (w < 0) continue;
                        if (s2 == s_eff && via < 0) {
                            EXPECT_NEAR(w, c->weight, 1e-9);
                        }
                        // The connector's weight from this split's table, and its factors.
                        if (via >= 0 && w >= 0 && !t2.connector.empty() && size_t(s) < t2.connector.size() &&
                            t2.connector[size_t(s)] > 0) {
                            EXPECT_NEAR(mis_weight_connector(t2, s, set), c->weight, 1e-9) << "split " << s2;
                        }
                        EXPECT_EQ(t2.connector.size(), fp.connector.size()) << "split " << s2;
                        if (t2.connector.size() == fp.connector.size()) {
                            for (size_t q = 0; q < fp.connector.size(); ++q)
                                EXPECT_NEAR(t2.connector[q], fp.connector[q], 1e-9 * fp.connector[q]) << "connector[" << q << "]";
                        }
                        // Densities recomputed from any split agree with those of the sampled split.
                        for (size_t q = 0; q < full.size(); ++q) {
                            EXPECT_NEAR(t2.p_light[q], fp.p_light[q], 1e-9 * std::abs(fp.p_light[q]) + 1e-30)
                                << "p_light[" << q << "] split " << s2 << " vs sampled s=" << s << " t=" << t;
                            EXPECT_NEAR(t2.p_sensor[q], fp.p_sensor[q], 1e-9 * std::abs(fp.p_sensor[q]) + 1e-30)
                                << "p_sensor[" << q << "] split " << s2 << " vs sampled s=" << s << " t=" << t;
                        }
                        sum += w;
                    }
                    // Every connector that can produce this path joins the sum.
                    for (size_t j = 0; j < fp.connector.size(); ++j)
                        if (fp.connector[j] > 0) {
                            const double wc = mis_weight_connector(fp, int(j), set);
                            if (wc >= 0) sum += wc;
                        }
                    // Walks and connections compute each density by the same function from the same
                    // stored positions, so every split sees the same table and the sum is exact.
                    EXPECT_NEAR(sum, 1.0, 1e-9) << "s=" << s << " t=" << t << " k=" << k << [&] {
                        std::string m;
                        for (size_t q = 0; q < full.size(); ++q)
                            m += "\n v" + std::to_string(q) + " pL=" + std::to_string(fp.p_light[q]) +
                                 " pE=" + std::to_string(fp.p_sensor[q]) + " delta=" + std::to_string(fp.delta[q]);
                        for (int s2 = 0; s2 <= int(full.size()); ++s2) {
                            FullPathPdfs t2 = fp;
                            m += "\n w(" + std::to_string(s2) + ")=" + std::to_string(weight_for_split(*scene, full, s2, set, &t2));
                        }
                        return m;
                    }();
                    ++out.paths;
                    out.max_vertices = std::max(out.max_vertices, int(full.size()));
                    if (::testing::Test::HasFailure()) return out;
                }
            }
    }
    EXPECT_EQ(cstats.bad_weights, 0u);
    return out;
}

ShapeDesc rect(const Mat4& m, const std::string& mat) {
    ShapeDesc s;
    s.type = ShapeType::Rectangle;
    s.to_world = m;
    s.material = mat;
    return s;
}

// A closed box [-1,1]^3 with the camera inside at z = -0.8 looking along +z.
SceneDesc box(const std::string& walls, const std::string& floor) {
    SceneDesc d = test::empty_scene(16, 16);
    d.sensor.to_world = Mat4::look_at({0, 0, -0.8}, {0, 0, 1}, {0, 1, 0});
    d.materials["white"] = test::diffuse("white", Rgb(0.7f));
    ConductorBsdf mirror;
    d.materials["mirror"] = MaterialDesc{"mirror", mirror, {}};
    ConductorBsdf glossy;
    glossy.alpha_u = glossy.alpha_v = 0.15f;
    d.materials["glossy"] = MaterialDesc{"glossy", glossy, {}};
    d.materials["glass"] = MaterialDesc{"glass", DielectricBsdf{}, {}};
    d.materials["black"] = MaterialDesc{"black", BlackBsdf{}, {}};
    d.shapes.push_back(rect(Mat4::translate({0, -1, 0}) * Mat4::rotate({1, 0, 0}, -90), floor));
    d.shapes.push_back(rect(Mat4::translate({0, 1, 0}) * Mat4::rotate({1, 0, 0}, 90), walls));
    d.shapes.push_back(rect(Mat4::translate({-1, 0, 0}) * Mat4::rotate({0, 1, 0}, 90), walls));
    d.shapes.push_back(rect(Mat4::translate({1, 0, 0}) * Mat4::rotate({0, 1, 0}, -90), walls));
    d.shapes.push_back(rect(Mat4::translate({0, 0, 1}) * Mat4::rotate({0, 1, 0}, 180), walls));
    d.shapes.push_back(rect(Mat4::translate({0, 0, -1}), walls));
    return d;
}

TEST(MisWeights, SumToOneDiffuseBoxAreaLight) {
    SceneDesc d = box("white", "white");
    ShapeDesc light = rect(Mat4::translate({0, 0.99, 0}) * Mat4::scale({0.3, 1, 0.3}) * Mat4::rotate({1, 0, 0}, 90), "black");
    light.emitter = EmitterDesc{Rgb(5.f), false};
    d.shapes.push_back(light);
    auto c = check_scene(d, 200, 6);
    EXPECT_GT(c.paths, 1000);
    EXPECT_GT(c.prefixed, 500);
}

// The mirror box with a diffuse floor and a point light: L S D ... paths through chains of mirrors.
SceneDesc mirror_box_point_light() {
    SceneDesc d = box("mirror", "white");
    LightDesc l;
    l.type = LightType::Point;
    l.position = {0.2, 0.5, 0.3};
    l.intensity = Rgb(2.f);
    d.lights.push_back(l);
    return d;
}

// The walls are planar mirrors, so the connector joins the strategies (issue 15 part 3): its
// weights and the ordinary ones sum to 1 together, for bdpt, path and light.
TEST(MisWeights, SumToOnePointLightPinholeWithMirrors) {
    SceneDesc d = mirror_box_point_light();
    auto c = check_scene(d, 200, 7);
    EXPECT_GT(c.paths, 500);
    EXPECT_GT(c.prefixed, 100);
    EXPECT_GT(c.connector_paths, 200);
}

// Smooth plastic walls: one BSDF with a delta lobe and a diffuse one, so a vertex may be S in one
// split (its walk took the mirror) and a connection point in another (through the substrate).
TEST(MisWeights, SumToOneSmoothPlasticBoxAreaLight) {
    SceneDesc d = box("plastic", "white");
    PlasticBsdf p;
    p.set_eta(1.5f);
    p.diffuse_reflectance = {0.6f, 0.4f, 0.3f};
    d.materials["plastic"] = MaterialDesc{"plastic", p, {}};
    p.alpha = 0.2f;
    d.materials["rough"] = MaterialDesc{"rough", p, {}};
    ShapeDesc ball;
    ball.type = ShapeType::Sphere;
    ball.center = {0, -0.6, 0.3};
    ball.radius = 0.3;
    ball.material = "rough";
    d.shapes.push_back(ball);
    ShapeDesc light = rect(Mat4::translate({0, 0.99, 0}) * Mat4::scale({0.3, 1, 0.3}) * Mat4::rotate({1, 0, 0}, 90), "black");
    light.emitter = EmitterDesc{Rgb(5.f), false};
    d.shapes.push_back(light);
    auto c = check_scene(d, 200, 6);
    EXPECT_GT(c.paths, 1000);
}

TEST(MisWeights, SumToOneGlossyGlassSphereLightAndSpot) {
    SceneDesc d = box("glossy", "white");
    ShapeDesc ball;
    ball.type = ShapeType::Sphere;
    ball.center = {0, -0.6, 0.3};
    ball.radius = 0.3;
    ball.material = "glass";
    d.shapes.push_back(ball);
    ShapeDesc lamp = ball;
    lamp.center = {0.5, 0.6, 0.5};
    lamp.radius = 0.1;
    lamp.material = "black";
    lamp.emitter = EmitterDesc{Rgb(20.f), false};
    d.shapes.push_back(lamp);
    LightDesc spot;
    spot.type = LightType::Spot;
    spot.to_world = Mat4::look_at({-0.5, 0.8, 0}, {0, -1, 0.3}, {0, 0, 1});
    spot.intensity = Rgb(3.f);
    spot.cutoff_angle = 40;
    spot.beam_width = 30;
    d.lights.push_back(spot);
    auto c = check_scene(d, 200, 6);
    EXPECT_GT(c.paths, 500);
    EXPECT_GT(c.prefixed, 100);
}

TEST(MisWeights, SumToOneOrthographicDirectionalAndEnvironment) {
    SceneDesc d = test::empty_scene(16, 16);
    d.sensor.type = SensorType::Orthographic;
    d.sensor.to_world = Mat4::look_at({0, 3, 0}, {0, 0, 0}, {0, 0, 1}) * Mat4::scale({1.5, 1.5, 1});
    d.materials["white"] = test::diffuse("white", Rgb(0.6f));
    ConductorBsdf mirror;
    d.materials["mirror"] = MaterialDesc{"mirror", mirror, {}};
    d.shapes.push_back(rect(Mat4::rotate({1, 0, 0}, -90) * Mat4::scale({3, 3, 1}), "white"));
    ShapeDesc ball;
    ball.type = ShapeType::Sphere;
    ball.center = {0.3, 0.5, 0};
    ball.radius = 0.4;
    ball.material = "mirror";
    d.shapes.push_back(ball);
    LightDesc sun;
    sun.type = LightType::Directional;
    sun.direction = {0.3, -1, 0.2};
    sun.irradiance = Rgb(2.f);
    d.lights.push_back(sun);
    LightDesc sky;
    sky.type = LightType::Constant;
    sky.radiance = Rgb(0.2f);
    d.lights.push_back(sky);
    auto c = check_scene(d, 300, 5);
    EXPECT_GT(c.paths, 500);
    EXPECT_GT(c.prefixed, 100);
}

TEST(MisWeights, SumToOneThinLens) {
    SceneDesc d = box("white", "glossy");
    d.sensor.type = SensorType::ThinLens;
    d.sensor.aperture_radius = 0.05f;
    d.sensor.focus_distance = 1.2f;
    ShapeDesc light = rect(Mat4::translate({0, 0.99, 0}) * Mat4::scale({0.3, 1, 0.3}) * Mat4::rotate({1, 0, 0}, 90), "black");
    light.emitter = EmitterDesc{Rgb(5.f), true};
    d.shapes.push_back(light);
    auto c = check_scene(d, 150, 5);
    EXPECT_GT(c.paths, 500);
    EXPECT_GT(c.prefixed, 100);
}

// t = 0 where it is the only strategy: a point light seen in a mirror through a thin lens
// (L S D S D D E), next to diffuse paths that every strategy shares. The lens is large so that
// light subpaths hit it often.
TEST(MisWeights, SumToOneThinLensPointLightMirrors) {
    SceneDesc d = mirror_box_point_light();
    d.sensor.type = SensorType::ThinLens;
    d.sensor.aperture_radius = 0.3f;
    d.sensor.focus_distance = 1.0f;
    auto c = check_scene(d, 1500, 6);
    EXPECT_GT(c.paths, 500);
    EXPECT_GT(c.prefixed, 100);
    EXPECT_GT(c.t0_paths, 20);
    EXPECT_GT(c.connector_paths, 200);  // bdpt's connectors beside t = 0, which it weighs
}

// Stress: a mirror box with one diffuse wall; paths of 60+ vertices keep finite weights that sum to 1.
TEST(MisWeights, LongSpecularChainsStayFinite) {
    SceneDesc d = box("mirror", "white");
    ShapeDesc light = rect(Mat4::translate({0, 0.99, 0}) * Mat4::scale({0.2, 1, 0.2}) * Mat4::rotate({1, 0, 0}, 90), "black");
    light.emitter = EmitterDesc{Rgb(5.f), false};
    d.shapes.push_back(light);
    auto c = check_scene(d, 40, 70);
    EXPECT_GE(c.max_vertices, 60);
    EXPECT_GT(c.prefixed, 20);
}

}  // namespace
}  // namespace omega
