#include "pathspace/lpe_classify.h"

#include <deque>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "pathspace/path_signature.h"

namespace omega {

namespace {

// Veach's letter for a vertex class: glossy scattering is non-delta, so D for Theorem 8.3.
char veach_letter(VertexClass c) { return c == VertexClass::S ? 'S' : 'D'; }

// The classes a surface vertex of this scene can take.
std::vector<VertexClass> surface_classes(const Scene& scene) {
    bool s = false, d = false, g = false;
    for (const Bsdf& b : scene.materials()) {
        const uint8_t lobes = bsdf_lobes(b);
        if (lobes & kLobeDelta) s = true;
        if (lobes & (kLobeDiffuse | kLobeGlossy)) (bsdf_is_glossy(b) ? g : d) = true;
    }
    std::vector<VertexClass> out;
    if (s) out.push_back(VertexClass::S);
    if (d) out.push_back(VertexClass::D);
    if (g) out.push_back(VertexClass::G);
    return out;
}

struct Found {
    bool any = false;              // some class the scene produces matches
    bool ours = false;             // ... and this integrator samples one of them
    bool local = false;            // ... some local strategy (bdpt) samples one of them
    std::string example;           // the shortest matching class, in Veach's notation
    std::string example_letters;   // ... as the expression sees it (with G)
};

// Breadth-first over the surface sequences the scene can produce, merging those that agree on
// everything the verdict depends on: the automaton state after them, their first and last
// Veach letters and whether they hold a DD edge (what sampleable_by and locally_sampleable read).
Found search(const LpeDfa& dfa, const EndpointClass& light, const EndpointClass& sensor,
             const std::vector<VertexClass>& symbols, IntegratorType integrator) {
    struct Node {
        uint8_t q;
        char first, last;
        bool dd;
        std::string veach, letters;
    };
    Found f;
    std::set<std::tuple<uint8_t, char, char, bool>> seen;
    std::deque<Node> queue;
    const uint8_t q0 = dfa.step(dfa.start, VertexClass::L);
    if (q0 == 0) return f;
    queue.push_back({q0, 0, 0, false, "", ""});
    seen.insert({q0, 0, 0, false});
    while (!queue.empty()) {
        Node n = std::move(queue.front());
        queue.pop_front();
        if (dfa.accepts(dfa.step(n.q, VertexClass::E))) {
            PathClass c{light, n.veach, sensor};
            if (!f.any) {
                f.example = c.regex();
                f.example_letters = "L " + n.letters + (n.letters.empty() ? "E" : " E");
            }
            f.any = true;
            f.ours = f.ours || sampleable_by(c, integrator);
            f.local = f.local || sampleable_by(c, IntegratorType::Bdpt);
            if (f.ours) return f;
        }
        for (VertexClass v : symbols) {
            const uint8_t q = dfa.step(n.q, v);
            if (q == 0) continue;
            const char l = veach_letter(v);
            const char first = n.first ? n.first : l;
            const bool dd = n.dd || (n.last == 'D' && l == 'D');
            if (!seen.insert({q, first, l, dd}).second) continue;
            Node m{q, first, l, dd, n.veach + l, n.letters};
            if (!m.letters.empty()) m.letters += ' ';
            m.letters += vertex_class_letter(v);
            queue.push_back(std::move(m));
        }
    }
    return f;
}

const char* integrator_name_words(IntegratorType t) {
    switch (t) {
        case IntegratorType::Path: return "the path tracer";
        case IntegratorType::Light: return "the light tracer";
        case IntegratorType::Bdpt: return "bidirectional path tracing";
    }
    return "?";
}

std::string letters_text(const std::vector<VertexClass>& symbols) {
    std::string out;
    for (VertexClass v : symbols) {
        if (!out.empty()) out += ", ";
        out += vertex_class_letter(v);
    }
    return out.empty() ? "none (no surface scatters)" : out;
}

}  // namespace

std::vector<std::string> aov_warnings(const Scene& scene, const LpeSet& aovs, IntegratorType integrator) {
    std::vector<std::string> out;
    if (aovs.empty()) return out;
    const SceneClasses sc = classify_scene(scene);
    const std::vector<VertexClass> symbols = surface_classes(scene);
    for (size_t i = 0; i < aovs.size(); ++i) {
        Found all;
        for (const EndpointClass& l : sc.lights) {
            Found f = search(aovs[i].forward, l, sc.sensor, symbols, integrator);
            if (f.any && !all.any) {
                all.example = f.example;
                all.example_letters = f.example_letters;
            }
            all.any = all.any || f.any;
            all.ours = all.ours || f.ours;
            all.local = all.local || f.local;
        }
        const std::string head = fmt::format("aov {} ({})", aovs.name(i), aovs[i].text);
        if (sc.lights.empty()) {
            out.push_back(head + ": black, the scene has no light");
        } else if (!all.any) {
            out.push_back(fmt::format("{}: black, no path this scene can produce matches it (its surface vertices can be "
                                      "{}; a path is L, surface vertices, E)",
                                      head, letters_text(symbols)));
        } else if (!all.local) {
            out.push_back(fmt::format("{}: black, every path it matches (such as {}: {}) has no DD edge, so no local "
                                      "path sampling strategy can produce it (Veach, Theorem 8.3)",
                                      head, all.example_letters, all.example));
        } else if (!all.ours) {
            out.push_back(fmt::format("{}: black, {} cannot sample the paths it matches (such as {}: {}); bdpt can",
                                      head, integrator_name_words(integrator), all.example_letters, all.example));
        }
    }
    return out;
}

}  // namespace omega
