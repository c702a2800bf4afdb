#include "pathspace/path_signature.h"

#include <algorithm>

namespace omega {

namespace {

bool glossy_alpha(float a) { return a > 0 && a < kGlossyAlpha; }

VertexClass walk_class(const PathVertex& v) {
    if (v.delta) return VertexClass::S;
    return v.bsdf ? nondelta_class(*v.bsdf) : VertexClass::D;
}

VertexClass joined_class(const PathVertex& v) { return v.bsdf ? nondelta_class(*v.bsdf) : VertexClass::D; }

}  // namespace

bool bsdf_is_glossy(const Bsdf& bsdf) {
    if (auto* c = std::get_if<ConductorBsdf>(&bsdf)) return glossy_alpha(std::min(c->alpha_u, c->alpha_v));
    if (auto* d = std::get_if<DielectricBsdf>(&bsdf)) return glossy_alpha(std::min(d->alpha_u, d->alpha_v));
    if (auto* p = std::get_if<PlasticBsdf>(&bsdf)) return glossy_alpha(p->alpha);
    return false;  // diffuse (Lambert or Oren-Nayar), thin dielectric (delta only), black
}

void strategy_signature(const std::vector<PathVertex>& light, const std::vector<PathVertex>& camera, int s, int t,
                        std::vector<VertexClass>& out) {
    out.clear();
    const int k = s + t - 1;
    out.resize(size_t(k + 1), VertexClass::D);
    // Index 0 of either subpath is an endpoint (and may not even be stored: s = 1 and t = 1
    // sample it afresh), so only the inner vertices are read.
    for (int i = 1; i < s; ++i) out[size_t(i)] = (i + 1 == s && t >= 1) ? joined_class(light[size_t(i)]) : walk_class(light[size_t(i)]);
    for (int j = 1; j < t; ++j) {
        const PathVertex& v = camera[size_t(j)];
        out[size_t(k - j)] = (j + 1 == t && s >= 1) ? joined_class(v) : walk_class(v);
    }
    out.front() = VertexClass::L;
    out.back() = VertexClass::E;
}

void lens_signature(const std::vector<PathVertex>& light, int s, std::vector<VertexClass>& out) {
    out.clear();
    for (int i = 0; i < s; ++i) out.push_back(walk_class(light[size_t(i)]));
    out.push_back(VertexClass::E);
    out.front() = VertexClass::L;
}

}  // namespace omega
