// Analytic scenes with closed-form answers, checked by z-tests on the estimated standard error.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cmath>

#include "render_harness.h"

namespace omega {
namespace {

// Float32 arithmetic along a path: allow this relative slack on top of the sampling error.
constexpr double kFloatRelSlack = 2e-6;

SceneDesc furnace(float rho, float le, int max_depth) {
    SceneDesc d = test::empty_scene(24, 24);
    d.integrator.max_depth = max_depth;
    d.integrator.rr_depth = 3;
    d.materials["wall"] = test::diffuse("wall", Rgb(rho));
    ShapeDesc s;
    s.type = ShapeType::Sphere;
    s.radius = 1.0;
    s.material = "wall";
    s.emitter = EmitterDesc{Rgb(le), true};
    d.shapes.push_back(s);
    return d;
}

double z_with_slack(const Film& film, double expected) {
    Rect c = film.crop();
    double diff = 0, var = 0;
    for (int y = c.y0; y < c.y1; ++y)
        for (int x = c.x0; x < c.x1; ++x) {
            PixelStats p = film.pixel(x, y);
            diff += (p.mean.x + p.mean.y + p.mean.z) / 3.0 - expected;
            var += (p.var_of_mean.x + p.var_of_mean.y + p.var_of_mean.z) / 3.0;
        }
    double n = double(c.area());
    double mean_diff = diff / n, se = std::sqrt(var) / n;
    double slack = kFloatRelSlack * expected;
    double excess = std::max(0.0, std::abs(mean_diff) - slack);
    return se > 0 ? excess / se : (excess > 0 ? INFINITY : 0.0);
}

class Furnace : public ::testing::TestWithParam<float> {};

TEST_P(Furnace, UnboundedDepthMatchesGeometricSeries) {
    float rho = GetParam();
    const float le = 0.5f;
    auto r = test::render(furnace(rho, le, -1), rho > 0.95f ? 64 : 32, 1);
    double expected = le / (1.0 - rho);
    double z = z_with_slack(r.film(), expected);
    EXPECT_LT(z, test::z_threshold(6)) << "rho " << rho << " mean " << r.report.error.image_mean << " expected " << expected;
    EXPECT_EQ(r.report.nonfinite, 0u);
}

TEST_P(Furnace, TruncatedDepthMatchesPartialSum) {
    float rho = GetParam();
    const float le = 1.f;
    for (int depth : {1, 2, 5}) {
        auto r = test::render(furnace(rho, le, depth), 16, 2);
        double expected = le * (1.0 - std::pow(double(rho), depth)) / (1.0 - rho);
        double z = z_with_slack(r.film(), expected);
        EXPECT_LT(z, test::z_threshold(18)) << "rho " << rho << " depth " << depth << " mean "
                                             << r.report.error.image_mean << " expected " << expected;
        EXPECT_EQ(r.report.nonfinite, 0u);
    }
}

INSTANTIATE_TEST_SUITE_P(Albedo, Furnace, ::testing::Values(0.5f, 0.9f, 0.99f));

// The test must be able to fail: a wrong albedo in the expectation is rejected.
TEST(FurnaceSanity, DetectsAWrongAnswer) {
    auto r = test::render(furnace(0.9f, 0.5f, -1), 64, 3);
    double wrong = 0.5 / (1.0 - 0.9) * 1.03;
    EXPECT_GT(z_with_slack(r.film(), wrong), test::z_threshold(1));
}

// A point light of intensity I at the centre of a diffuse sphere of radius R.
// First bounce: rho I / (pi R^2); each further bounce multiplies by rho.
TEST(PointLightInSphere, MatchesClosedForm) {
    const float rho = 0.7f, intensity = 3.f;
    const double radius = 2.0;
    for (int depth : {2, 3, -1}) {
        SceneDesc d = test::empty_scene(24, 24);
        d.integrator.max_depth = depth;
        d.materials["wall"] = test::diffuse("wall", Rgb(rho));
        ShapeDesc s;
        s.type = ShapeType::Sphere;
        s.radius = radius;
        s.material = "wall";
        d.shapes.push_back(s);
        LightDesc l;
        l.type = LightType::Point;
        l.position = {0, 0, 0};
        l.intensity = Rgb(intensity);
        d.lights.push_back(l);
        auto r = test::render(d, 16, 4);
        double first = rho * intensity / (kPiD * radius * radius);
        double series = depth < 0 ? 1.0 / (1.0 - rho) : (1.0 - std::pow(double(rho), depth - 1)) / (1.0 - rho);
        double z = z_with_slack(r.film(), first * series);
        EXPECT_LT(z, test::z_threshold(3)) << "depth " << depth << " mean " << r.report.error.image_mean
                                            << " expected " << first * series;
        EXPECT_EQ(r.report.nonfinite, 0u);
    }
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// The breakdown by length (App. 8.A): in the furnace, the paths of k edges carry
// le rho^(k-1) of the measurement le / (1 - rho), the fraction (1 - rho) rho^(k-1), and the
// paths longer than the breakdown's length the rest, rho^max. One z-test per length (Bonferroni).
// With expected_rho != rho the expectation is wrong, and must be rejected.
int furnace_length_failures(IntegratorType type, double rho, double expected_rho, long long spp, uint64_t seed) {
    SceneDesc d = furnace(float(rho), 1.f, -1);
    d.sensor.film.width = d.sensor.film.height = 8;
    d.integrator.type = type;
    BreakdownDesc bd;
    bd.max_length = 5;
    auto r = test::render_breakdown(d, spp, bd, seed, 2);
    const BreakdownReport rep = test::breakdown(r);
    int failures = 0;
    const double bound = test::z_threshold(bd.max_length + 1);
    for (int k = 1; k <= bd.max_length + 1; ++k) {
        const bool longer = k > bd.max_length;
        const double expected =
            longer ? std::pow(expected_rho, bd.max_length) : (1 - expected_rho) * std::pow(expected_rho, k - 1);
        const BreakdownRow* row = test::breakdown_row(rep, "length", longer ? "longer" : fmt::format("k={}", k));
        if (!row) {
            ++failures;
            continue;
        }
        const double z = (row->fraction - expected) / std::max(row->fraction_stderr, 1e-300);
        if (std::abs(z) > bound) ++failures;
        if (expected_rho == rho) {
            EXPECT_LT(std::abs(z), bound) << integrator_name(type) << " k " << k << " fraction " << row->fraction
                                          << " +- " << row->fraction_stderr << " expected " << expected;
        }
    }
    return failures;
}

TEST(FurnaceBreakdown, LengthFractionsAreGeometric) {
    for (IntegratorType type : {IntegratorType::Path, IntegratorType::Bdpt, IntegratorType::Light})
        EXPECT_EQ(furnace_length_failures(type, 0.6, 0.6, 64, 11), 0) << integrator_name(type);
}

TEST(FurnaceBreakdown, DetectsAWrongAlbedo) {
    EXPECT_GT(furnace_length_failures(IntegratorType::Path, 0.6, 0.64, 64, 12), 0);
}

}  // namespace
}  // namespace omega
