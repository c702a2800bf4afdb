#pragma once
// The signature of a full path: the class of each of its vertices x_0 .. x_k, light first
// (pathspace/lpe.h names the classes). What light path expressions match, and what a breakdown
// of the measurement by path class and length would key on (the length is size() - 1).
//
// A vertex's class is decided the same way by every integrator, so that the share of the image
// an expression selects is one quantity all of them estimate:
//  - x_0 is L and x_k is E, whatever they are (a point on an area light, a lens point);
//  - a surface vertex inside a walk is S if the walk continued through a delta lobe, otherwise
//    D or G by its BSDF (vertex_scatter_class);
//  - a vertex where two subpaths are joined is D or G: a connection evaluates only the
//    non-delta part of the BSDF there.
#include <vector>

#include "pathspace/lpe.h"
#include "pathspace/vertex.h"

namespace omega {

// A BSDF whose non-delta scattering is glossy: a microfacet lobe with alpha < kGlossyAlpha.
bool bsdf_is_glossy(const Bsdf& bsdf);

// Class of a non-delta scattering event at this BSDF: G or D.
inline VertexClass nondelta_class(const Bsdf& bsdf) { return bsdf_is_glossy(bsdf) ? VertexClass::G : VertexClass::D; }
// Class of a scattering event that went through a delta lobe or not.
inline VertexClass scatter_class(const Bsdf& bsdf, bool delta) { return delta ? VertexClass::S : nondelta_class(bsdf); }

// The signature of BDPT strategy (s, t): light[0..s) then camera[t-1 .. 0]. For s = 1 and t = 1
// the sampled endpoints are L and E whatever stands in the subpath. Clears and fills `out`
// (callers keep it as scratch: no allocation once warmed up). Called on the thread that made
// the contribution.
void strategy_signature(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s, int t,
                        std::vector<VertexClass>& out);
// Strategy t = 0: the light walk's first s vertices reached the lens (the walk's own last edge).
void lens_signature(const std::vector<PathVertex>& light, int s, std::vector<VertexClass>& out);

}  // namespace omega
