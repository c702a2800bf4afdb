#pragma once
// Power heuristic (beta = 2), Veach ch. 9. Both densities must be in the same measure.
#include <cmath>

namespace omega {

inline float power_heuristic(float pdf_a, float pdf_b) {
    if (std::isinf(pdf_a)) return 1.f;
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    return a + b > 0 ? a / (a + b) : 0.f;
}

}  // namespace omega
