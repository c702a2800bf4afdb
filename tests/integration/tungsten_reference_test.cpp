// Agreement with an independent renderer: scenes of ../shared/scenes/materials rendered by Omega
// (through the Mitsuba importer) against Tungsten's reference.exr, by per-region z-tests (see
// tungsten_compare.h). The references were rendered with Tungsten's own model of each material,
// so this checks our reading of that model (plastic.cpp's header) end to end: importer defaults,
// BSDF, sampling and integrator.
#include "tungsten_compare.h"

namespace omega {
namespace {

// Shapes in file order: floor, light, then the four spheres left to right.
const std::vector<std::string> kPlastic = {"floor", "light", "smooth plastic (red)", "rough GGX 0.05 (green)",
                                           "rough GGX 0.2 (blue)", "rough GGX 0.5 (yellow)"};

// Path tracing: 2048 spp, about 10 s on 2 threads, region noise 0.2-0.6%.
TEST(TungstenReference, PlasticSpheresPath) {
    tungsten::compare_with_reference("plastic-spheres", IntegratorType::Path, 2048, "path", kPlastic);
}

// Bdpt meets the coat from both ends (light subpaths in importance mode, the smooth coat's mirror
// choice, connections through eval): fewer spp for the same time.
TEST(TungstenReference, PlasticSpheresBdpt) {
    tungsten::compare_with_reference("plastic-spheres", IntegratorType::Bdpt, 512, "bdpt", kPlastic);
}

}  // namespace
}  // namespace omega
