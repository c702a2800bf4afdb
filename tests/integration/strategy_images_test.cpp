// Each BDPT strategy converges on its own: the unweighted image of strategy (s, t) is by itself
// an unbiased estimate of all paths of length k = s + t - 1 it can sample, so in a diffuse box
// lit by an area light every strategy of a given length agrees with every other (t-test over
// independent seeds), and the MIS-weighted images of one length add up to the same value.
#include <gtest/gtest.h>

#include <cmath>

#include "render_harness.h"
#include "scene/scene_parser.h"

namespace omega {
namespace {

struct Stat {
    double mean = 0, se = 0;
};

Stat stat_of(const std::vector<double>& v) {
    double m = 0;
    for (double x : v) m += x;
    m /= double(v.size());
    double ss = 0;
    for (double x : v) ss += (x - m) * (x - m);
    return {m, std::sqrt(ss / double(v.size() - 1) / double(v.size()))};
}

TEST(StrategyImages, EveryStrategyOfALengthEstimatesTheSameIntegral) {
    SceneDesc d = parse_scene_file(OMEGA_SOURCE_DIR "/scenes/cornell-box.yaml");
    d.sensor.film.width = d.sensor.film.height = 16;
    d.sensor.film.filter = FilterType::Box;
    d.sensor.film.filter_radius = 0.5f;
    d.integrator.type = IntegratorType::Bdpt;
    d.integrator.max_depth = 3;
    auto scene = Scene::build(d);
    const int runs = 10, max_k = 3;
    const long long spp = 16;
    // samples[k][s][run]: unweighted image means; weighted sums per length.
    std::vector<std::vector<std::vector<double>>> unweighted(max_k + 1, std::vector<std::vector<double>>(max_k + 1));
    std::vector<std::vector<double>> weighted_sum(max_k + 1);
    for (int r = 0; r < runs; ++r) {
        RenderSettings rs;
        rs.halt.spp = spp;
        rs.seed = uint64_t(1000 + r);
        rs.integrator = d.integrator;
        rs.strategy_images_max_k = max_k;
        RenderSession session(*scene, rs);
        PassReport rep = session.run();
        ASSERT_EQ(rep.nonfinite, 0u);
        const StrategyImages* si = session.strategy_images();
        ASSERT_NE(si, nullptr);
        for (int k = 2; k <= max_k; ++k) {
            double wsum = 0;
            for (int s = 0; s <= k; ++s) {
                int t = k + 1 - s;
                unweighted[size_t(k)][size_t(s)].push_back(si->image_mean(s, t, false, spp));
                wsum += si->image_mean(s, t, true, spp);
            }
            weighted_sum[size_t(k)].push_back(wsum);
        }
    }
    const int comparisons = 2 * 4 + 2 * 5;
    const double bound = test::z_threshold(comparisons, 1e-3) * 1.3;  // t with 9 dof is heavier-tailed than z
    for (int k = 2; k <= max_k; ++k) {
        Stat ref = stat_of(weighted_sum[size_t(k)]);
        EXPECT_GT(ref.mean, 0.0);
        for (int s = 0; s <= k; ++s) {
            Stat st = stat_of(unweighted[size_t(k)][size_t(s)]);
            double z = (st.mean - ref.mean) / std::sqrt(st.se * st.se + ref.se * ref.se);
            EXPECT_LT(std::abs(z), bound) << "k=" << k << " s=" << s << " t=" << k + 1 - s << ": " << st.mean
                                          << " +- " << st.se << " vs MIS " << ref.mean << " +- " << ref.se;
        }
    }
    // The test can fail: paths of length 2 and 3 carry clearly different energy.
    Stat k2 = stat_of(weighted_sum[2]), k3 = stat_of(weighted_sum[3]);
    EXPECT_GT(std::abs(k2.mean - k3.mean) / std::sqrt(k2.se * k2.se + k3.se * k3.se), bound);
}

}  // namespace
}  // namespace omega
