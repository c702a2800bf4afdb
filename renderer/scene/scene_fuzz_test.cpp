// Random mutations of a valid scene must parse or throw SceneError, nothing else, never crash.
#include <gtest/gtest.h>

#include <random>

#include "scene/scene_parser.h"
#include "scene/test_helpers.h"

using namespace omega;

TEST(SceneFuzz, MutationsParseOrThrowSceneError) {
    omega::test::TempDir dir;
    dir.write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const std::string virtual_path = (dir.path / "scene.yaml").string();
    const std::string base = R"(omega: 1
integrator: {type: path, max_depth: 16, rr_depth: 5}
sensor:
  type: perspective
  fov: 19.5
  to_world: [{translate: [0, 1, 0]}, {rotate: {axis: [0, 1, 0], angle: 20}}, {scale: 2}]
  film: {width: 64, height: 64, filter: gaussian, stddev: 0.5, crop: [0, 0, 32, 32]}
  spp: 4
materials:
  white: {type: diffuse, reflectance: [0.725, 0.71, 0.68]}
  gold: {type: conductor, eta: [0.2, 0.9, 1.1], k: [3.9, 2.4, 2.1], alpha: 0.1, distribution: beckmann}
  glass: {type: dielectric, int_ior: bk7, ext_ior: air}
  light: {type: black}
shapes:
  - {type: rectangle, to_world: {matrix: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}, material: white}
  - {type: cube, to_world: {look_at: {origin: [0, 1, 6.8], target: [0, 1, 0], up: [0, 1, 0]}}, material: gold}
  - {type: sphere, center: [0, 0.5, 0], radius: 0.3, material: glass}
  - {type: mesh, file: m.obj, material: {type: diffuse, reflectance: 0.5}}
  - {type: disk, material: light, emitter: {type: area, radiance: [17, 12, 4]}}
lights:
  - {type: point, position: [0, 1.9, 0], intensity: [5, 5, 5]}
  - {type: spot, intensity: 1, cutoff_angle: 30, beam_width: 20}
  - {type: directional, direction: [0, -1, 0], irradiance: [1, 1, 1]}
  - {type: constant, radiance: [1, 1, 1]}
)";
    ASSERT_NO_THROW(parse_scene_string(base, virtual_path));

    const std::string interesting = "{}[]:,-#&*!|>'\"%@` \n\t0123456789.eE+-naif";
    std::mt19937 rng(12345);
    auto pick = [&](size_t n) { return std::uniform_int_distribution<size_t>(0, n - 1)(rng); };
    int ok = 0, errors = 0;
    for (int iter = 0; iter < 2000; ++iter) {
        std::string s = base;
        int edits = 1 + int(pick(4));
        for (int e = 0; e < edits && !s.empty(); ++e) {
            switch (pick(5)) {
                case 0: s[pick(s.size())] = char(pick(256)); break;                             // byte flip
                case 1: s[pick(s.size())] = interesting[pick(interesting.size())]; break;       // syntax char
                case 2: s.resize(pick(s.size())); break;                                        // truncation
                case 3: s.erase(pick(s.size()), 1 + pick(8)); break;                            // deletion
                case 4: s.insert(pick(s.size()), 1, interesting[pick(interesting.size())]); break;  // insertion
            }
        }
        try {
            parse_scene_string(s, virtual_path);
            ++ok;
        } catch (const SceneError& err) {
            ++errors;
            // Every message names the file first.
            ASSERT_EQ(std::string(err.what()).rfind(virtual_path + ":", 0), 0u) << err.what();
        } catch (const std::exception& err) {
            FAIL() << "iteration " << iter << ": " << typeid(err).name() << ": " << err.what() << "\n--- input ---\n" << s;
        } catch (...) {
            FAIL() << "iteration " << iter << ": unknown exception\n--- input ---\n" << s;
        }
    }
    // Both outcomes must actually occur, or the mutations are too weak or too strong to test anything.
    EXPECT_GT(ok, 20);
    EXPECT_GT(errors, 200);
}
