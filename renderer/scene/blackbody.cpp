#include "scene/blackbody.h"

#include <cmath>

namespace omega {

namespace {

// One lobe of the multi-lobe fit: a Gaussian with different widths left and right of its mean.
double lobe(double lambda, double mu, double s_left, double s_right) {
    double t = (lambda - mu) / (lambda < mu ? s_left : s_right);
    return std::exp(-0.5 * t * t);
}
double cie_x(double l) {
    return 1.056 * lobe(l, 599.8, 37.9, 31.0) + 0.362 * lobe(l, 442.0, 16.0, 26.7) - 0.065 * lobe(l, 501.1, 20.4, 26.2);
}
double cie_y(double l) { return 0.821 * lobe(l, 568.8, 46.9, 40.5) + 0.286 * lobe(l, 530.9, 16.3, 31.1); }
double cie_z(double l) { return 1.217 * lobe(l, 437.0, 11.8, 36.0) + 0.681 * lobe(l, 459.0, 26.0, 13.8); }

}  // namespace

double planck_per_nm(double wavelength_nm, double kelvin) {
    constexpr double h = 6.62607015e-34, c = 299792458.0, k = 1.380649e-23;
    const double l = wavelength_nm * 1e-9;
    const double l5 = l * l * l * l * l;
    return 2.0 * h * c * c / (l5 * std::expm1(h * c / (l * k * kelvin))) * 1e-9;
}

Rgb blackbody_linear_srgb(double kelvin) {
    double X = 0, Y = 0, Z = 0, norm = 0;
    for (int nm = 360; nm <= 830; ++nm) {  // 1 nm steps, as Mitsuba integrates
        const double l = nm, b = planck_per_nm(l, kelvin);
        X += cie_x(l) * b;
        Y += cie_y(l) * b;
        Z += cie_z(l) * b;
        norm += cie_y(l);
    }
    X /= norm, Y /= norm, Z /= norm;
    return {float(3.2404542 * X - 1.5371385 * Y - 0.4985314 * Z), float(-0.9692660 * X + 1.8760108 * Y + 0.0415560 * Z),
            float(0.0556434 * X - 0.2040259 * Y + 1.0572252 * Z)};
}

}  // namespace omega
