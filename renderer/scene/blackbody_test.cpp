// Black-body colours against closed forms that share no code with the conversion: Planck's law
// by hand at one wavelength, and the Planckian locus of Kim et al. (2002, the cubic fit of the
// CIE 1931 chromaticity of a black body) for the colour.
#include "scene/blackbody.h"

#include <gtest/gtest.h>

#include <cmath>

#include "scene/mitsuba_importer.h"
#include "scene/test_helpers.h"

using namespace omega;

namespace {

// Kim, Kang, Kim, Lee, Hong, Kim: "Design of advanced color temperature control system for HDTV
// applications" (2002), valid 1667-25000 K.
Vec2 planckian_locus(double T) {
    double x = T >= 4000 ? -3.0258469e9 / (T * T * T) + 2.1070379e6 / (T * T) + 0.2226347e3 / T + 0.240390
                         : -0.2661239e9 / (T * T * T) - 0.2343589e6 / (T * T) + 0.8776956e3 / T + 0.179910;
    double y = T >= 4000   ? 3.0817580 * x * x * x - 5.87338670 * x * x + 3.75112997 * x - 0.37001483
               : T >= 2222 ? -0.9549476 * x * x * x - 1.37418593 * x * x + 2.09137015 * x - 0.16748867
                           : -1.1063814 * x * x * x - 1.34811020 * x * x + 2.18555832 * x - 0.20219683;
    return {float(x), float(y)};
}

// Linear sRGB back to CIE XYZ (the inverse of the matrix the conversion uses, IEC 61966-2-1).
Vec3d to_xyz(const Rgb& c) {
    return {0.4124564 * c.x + 0.3575761 * c.y + 0.1804375 * c.z, 0.2126729 * c.x + 0.7151522 * c.y + 0.0721750 * c.z,
            0.0193339 * c.x + 0.1191920 * c.y + 0.9503041 * c.z};
}

}  // namespace

TEST(Blackbody, PlanckMatchesAHandComputation) {
    // 2hc^2 / lambda^5 / (exp(hc / (lambda k T)) - 1) at 555 nm, 5000 K, per nm: 12740.3.
    EXPECT_NEAR(planck_per_nm(555, 5000), 12740.3, 0.1);
}

TEST(Blackbody, ChromaticityLiesOnThePlanckianLocus) {
    for (double T : {2500.0, 3000.0, 4500.0, 6504.0, 10000.0, 20000.0}) {
        Vec3d xyz = to_xyz(blackbody_linear_srgb(T));
        double s = xyz.x + xyz.y + xyz.z;
        Vec2 want = planckian_locus(T);
        // The matching functions are a fit within ~1%; the locus fit is within ~0.001.
        EXPECT_NEAR(xyz.x / s, want.x, 0.003) << T << " K";
        EXPECT_NEAR(xyz.y / s, want.y, 0.003) << T << " K";
    }
    // D65 is close to a 6504 K black body: nearly neutral in sRGB.
    Rgb d = blackbody_linear_srgb(6504);
    EXPECT_NEAR(d.x / d.y, 1.0, 0.07);
    EXPECT_NEAR(d.z / d.y, 1.0, 0.07);
}

TEST(Blackbody, LuminanceIsTheYBarWeightedMeanRadiance) {
    // Y (the y-bar-weighted mean of the radiance per nm) lies within the range of Planck's law
    // over where y-bar is large, and near its value at y-bar's peak.
    for (double T : {3000.0, 5000.0, 8000.0}) {
        double Y = to_xyz(blackbody_linear_srgb(T)).y;
        EXPECT_NEAR(Y / planck_per_nm(555, T), 1.0, 0.05) << T << " K";
    }
}

TEST(Blackbody, MitsubaBothSyntaxesImportWithTheirScale) {
    auto import = [](const std::string& radiance) {
        return import_mitsuba_string("<scene version=\"3.0.0\"><emitter type=\"point\">" + radiance +
                                         "</emitter></scene>",
                                     "scene.xml");
    };
    Rgb want = blackbody_linear_srgb(3200);
    SceneDesc a = import(R"(<blackbody name="intensity" temperature="3200K" scale="0.5"/>)");
    SceneDesc b = import(R"(<spectrum name="intensity" type="blackbody"><float name="temperature" value="3200"/></spectrum>)");
    ASSERT_EQ(a.lights.size(), 1u);
    ASSERT_EQ(b.lights.size(), 1u);
    const Rgb ia = a.lights[0].intensity;
    const Rgb ib = b.lights[0].intensity;
    EXPECT_FLOAT_EQ(ia.x, 0.5f * want.x);
    EXPECT_FLOAT_EQ(ia.z, 0.5f * want.z);
    EXPECT_FLOAT_EQ(ib.y, want.y);
    EXPECT_FALSE(test::has_warning(a, "blackbody")) << test::all_warnings(a);
    EXPECT_FALSE(test::has_warning(a, "not supported")) << test::all_warnings(a);
    std::string e = test::scene_error_of([&] { import(R"(<blackbody name="intensity" temperature="-5K"/>)"); });
    EXPECT_NE(e.find("scene.xml:1: emitter[0]"), std::string::npos) << e;
    EXPECT_NE(e.find("temperature must be positive"), std::string::npos) << e;
}
