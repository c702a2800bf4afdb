#pragma once
// The one place where densities change measure (Veach eq. 8.10).
//   p_area(x') = p_sa(w) * |cos theta'| / |x - x'|^2
// where theta' is the angle at the receiving vertex x' between its normal and the edge.
// Delta densities (point lights, pinholes, mirrors) are never converted: callers keep them
// as discrete probabilities and flag the vertex as S.
#include "math/vec.h"

namespace omega {

inline float convert_sa_to_area(float pdf_sa, float dist_sq, float abs_cos_at_receiver) {
    return pdf_sa * abs_cos_at_receiver / dist_sq;
}

inline float convert_area_to_sa(float pdf_area, float dist_sq, float abs_cos_at_receiver) {
    // A grazing receiver has no solid-angle density to speak of: report 0, never Inf.
    return abs_cos_at_receiver > 0 ? pdf_area * dist_sq / abs_cos_at_receiver : 0.f;
}

}  // namespace omega
