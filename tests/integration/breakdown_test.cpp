// The measurement-contribution breakdown (integrator/breakdown.h) through whole renders: the
// classes and the lengths each partition the measurement, the total is the film's mean, the
// report does not depend on the thread count, and the integrators agree class by class.
// (The furnace's lengths and the form factor's direct class are in furnace_test.cpp and
// form_factor_test.cpp, next to their closed forms.)
#include <gtest/gtest.h>

#include <cmath>

#include "render_harness.h"

namespace omega {
namespace {

// Mean over the region of the pixels' luminance: what the breakdown's total estimates.
double film_mean_luminance(const Film& film, const Rect& region) {
    double sum = 0;
    for (int y = region.y0; y < region.y1; ++y)
        for (int x = region.x0; x < region.x1; ++x) {
            const Vec3d m = film.pixel(x, y).mean;
            sum += 0.2126 * m.x + 0.7152 * m.y + 0.0722 * m.z;
        }
    return sum / double(region.area());
}

SceneDesc caustic_scene(IntegratorType type) {
    SceneDesc d = test::glass_caustic_scene(0.15, 20.f);
    d.sensor.film.width = d.sensor.film.height = 12;
    d.integrator.type = type;
    return d;
}

TEST(Breakdown, ClassesAndLengthsPartitionTheFilm) {
    for (IntegratorType type : {IntegratorType::Path, IntegratorType::Light, IntegratorType::Bdpt})
        for (bool use_box : {false, true}) {
            BreakdownDesc bd;
            bd.max_length = 3;  // some paths are longer: the "longer" row must close the sum
            if (use_box) bd.box = Rect{3, 2, 9, 7};
            auto r = test::render_breakdown(caustic_scene(type), 8, bd, 5, 2);
            const BreakdownReport rep = test::breakdown(r);
            double classes = 0, lengths = 0;
            for (const auto* c : rep.of_kind("class")) classes += c->fraction;
            for (const auto* l : rep.of_kind("length")) {
                lengths += l->fraction;
                // A length's fraction is the sum of its classes' (an identity, up to rounding).
                double of_length = 0;
                for (const auto* c : rep.of_kind("class"))
                    if (c->length == l->length) of_length += c->fraction;
                EXPECT_NEAR(l->fraction, of_length, 1e-12) << integrator_name(type) << " " << l->name;
            }
            EXPECT_NEAR(classes, 1.0, 1e-12) << integrator_name(type);
            EXPECT_NEAR(lengths, 1.0, 1e-12) << integrator_name(type);
            ASSERT_NE(test::breakdown_row(rep, "length", "longer"), nullptr) << integrator_name(type);
            // The total is the film's mean over the region, on the same scale (float rounding).
            const BreakdownRow* all = test::breakdown_row(rep, "total", "all");
            ASSERT_NE(all, nullptr);
            const double film = film_mean_luminance(r.film(), bd.box.value_or(r.film().crop()));
            EXPECT_GT(film, 0);
            EXPECT_NEAR(all->mu, film, 1e-5 * film) << integrator_name(type) << " box " << use_box;
        }
}

TEST(Breakdown, SameReportForAnyThreadCount) {
    for (IntegratorType type : {IntegratorType::Path, IntegratorType::Bdpt}) {
        BreakdownDesc bd;
        auto one = test::render_breakdown(caustic_scene(type), 4, bd, 9, 1, 32);
        auto two = test::render_breakdown(caustic_scene(type), 4, bd, 9, 2, 4);
        EXPECT_EQ(breakdown_csv(test::breakdown(one)), breakdown_csv(test::breakdown(two))) << integrator_name(type);
    }
}

// Path, light and bdpt estimate the same mu^m for every class the light tracer can reach (a
// path ending S E cannot be light traced; this camera sees no specular surface), by z-test.
TEST(Breakdown, IntegratorsAgreeByClass) {
    BreakdownDesc bd;
    bd.max_length = 4;
    const BreakdownReport path = test::breakdown(test::render_breakdown(caustic_scene(IntegratorType::Path), 64, bd, 1, 2));
    const BreakdownReport light = test::breakdown(test::render_breakdown(caustic_scene(IntegratorType::Light), 16, bd, 2, 2));
    const BreakdownReport bdpt = test::breakdown(test::render_breakdown(caustic_scene(IntegratorType::Bdpt), 16, bd, 3, 2));
    const auto classes = bdpt.of_kind("class");
    ASSERT_GE(classes.size(), 3u);
    bool has_caustic = false;
    const double bound = test::z_threshold(2 * int(classes.size()));
    for (const auto* c : classes) {
        has_caustic = has_caustic || c->name == "L S S D E";
        for (const BreakdownReport* other : {&path, &light}) {
            const BreakdownRow* o = test::breakdown_row(*other, "class", c->name);
            const double mu = o ? o->mu : 0, se = o ? o->mu_stderr : 0;
            const double z = (mu - c->mu) / std::sqrt(se * se + c->mu_stderr * c->mu_stderr + 1e-300);
            EXPECT_LT(std::abs(z), bound) << c->name << ": bdpt " << c->mu << " +- " << c->mu_stderr << ", other "
                                          << mu << " +- " << se;
        }
    }
    EXPECT_TRUE(has_caustic) << "the glass ball's caustic class is missing";
}

}  // namespace
}  // namespace omega
