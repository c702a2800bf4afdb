#include "bsdf/metals.h"

namespace omega {

// RGB (eta, k) from the table in Benedikt Bitterli's Tungsten renderer (ComplexIorData.hpp), which
// reduces the measured spectral data shipped with Mitsuba 0.5 / pbrt-v3 (Palik et al.) to linear
// sRGB. The same numbers appear in Nori and Yocto/GL.
std::optional<std::pair<Rgb, Rgb>> named_metal_ior(std::string_view name) {
    struct Entry {
        std::string_view name;
        Rgb eta, k;
    };
    static constexpr Entry kTable[] = {
        {"Au", {0.1431189557f, 0.3749570432f, 1.4424785571f}, {3.9831604247f, 2.3857207478f, 1.6032152899f}},
        {"Ag", {0.1552646489f, 0.1167232965f, 0.1383806959f}, {4.8283433224f, 3.1222459278f, 2.1469504455f}},
        {"Cu", {0.2004376970f, 0.9240334304f, 1.1022119527f}, {3.9129485033f, 2.4528477015f, 2.1421879552f}},
        {"Al", {1.6574599595f, 0.8803689579f, 0.5212287346f}, {9.2238691996f, 6.2695232477f, 4.8370012281f}},
    };
    for (const Entry& e : kTable)
        if (e.name == name) return std::pair{e.eta, e.k};
    return std::nullopt;
}

}  // namespace omega
