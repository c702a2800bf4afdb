#pragma once
// A black body's emitted radiance as Omega's linear sRGB (Rec. 709 primaries, D65 white), for
// Mitsuba's `blackbody` spectra.
//
// Convention (Mitsuba 0.6's BlackBodySpectrum, which Mitsuba 3 keeps): Planck's law in
// W m^-2 sr^-1 nm^-1, integrated against the CIE 1931 2-degree matching functions over
// 360-830 nm and divided by the integral of y-bar, so that Y is the y-bar-weighted mean of the
// spectral radiance; XYZ then goes to linear sRGB by the standard matrix. Mitsuba's RGB builds
// take the same path (Spectrum::fromContinuousSpectrum). The matching functions are Wyman, Sloan
// and Shirley's multi-lobe fit ("Simple Analytic Approximations to the CIE XYZ Color Matching
// Functions", JCGT 2013), within about 1% of the tables: an approximation that moves a colour by
// far less than the RGB rendering of a spectrum already does.
#include "math/vec.h"

namespace omega {

// kelvin > 0. Components may be slightly negative for very hot bodies outside the sRGB gamut;
// the caller clamps.
Rgb blackbody_linear_srgb(double kelvin);

// Planck's law: spectral radiance in W m^-2 sr^-1 nm^-1 at wavelength_nm.
double planck_per_nm(double wavelength_nm, double kelvin);

}  // namespace omega
