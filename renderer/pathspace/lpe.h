#pragma once
// Light path expressions (LPEs): the full-path regular expressions of Veach 8.3.2 used as a
// query over the image. An expression names a set of paths by the classes of their vertices,
// written light to eye ("L S+ D E": caustics); an AOV is the part of the measurement those paths
// carry. Expressions compile once to a deterministic automaton over the vertex classes, so
// matching a contribution is one table lookup per vertex.
//
// Vertex classes (one per vertex of a full path x_0 .. x_k):
//   L  x_0, the point on the emitter;  E  x_k, the point on the sensor;
//   S  a surface vertex whose scattering went through a delta lobe (mirror, smooth glass);
//   G  a non-delta scattering at a glossy BSDF: a microfacet lobe with roughness
//      alpha < kGlossyAlpha (rough conductor, rough dielectric, rough plastic);
//   D  any other non-delta scattering (diffuse, rough surfaces with alpha >= kGlossyAlpha).
// Writing `D` in an expression that does not mention `G` matches D or G (every non-delta
// vertex), so expressions written with S and D alone partition path space as in Veach; once an
// expression mentions `G`, its `D` means only the non-glossy vertices.
//
// Syntax (whitespace ignored): L E S D G, `.` any class, `|` alternation, `( )` grouping,
// postfix `*` `+` `?`, and bounds `{n}` `{n,m}` `{n,}` `{,m}` (at most kMaxBound). A bound on
// the whole path is a bound on what lies between L and E: `L .{0,3} E` is every path of at
// most 4 edges.
#include <array>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace omega {

enum class VertexClass : uint8_t { L = 0, E = 1, S = 2, D = 3, G = 4 };
constexpr int kVertexClasses = 5;
char vertex_class_letter(VertexClass c);

// Roughness below which a non-delta microfacet lobe counts as glossy (G). Beckmann/GGX alpha.
constexpr float kGlossyAlpha = 0.3f;
constexpr int kMaxBound = 32;       // largest n or m in {n,m}
constexpr int kMaxDfaStates = 254;  // state 255 is never used; 0 is the dead state
constexpr int kMaxAovs = 32;        // AOVs per film (a contribution's matches fit in a uint32 mask)

// Parse or compile failure. what(): "aov expression 'L S+ ( E': column 8: expected ')'".
struct LpeError : std::invalid_argument {
    LpeError(const std::string& expr, int column, const std::string& why);
    std::string expr;
    int column;  // 1-based; 0 when the message is about the whole expression
};

// A deterministic automaton over vertex classes. State 0 is dead (absorbing, never accepts);
// `start` is where matching begins.
struct LpeDfa {
    std::vector<std::array<uint8_t, kVertexClasses>> next;
    std::vector<uint8_t> accept;  // per state
    uint8_t start = 1;

    uint8_t step(uint8_t state, VertexClass c) const { return next[state][size_t(c)]; }
    bool accepts(uint8_t state) const { return accept[state] != 0; }
    bool matches(std::span<const VertexClass> path) const;  // the whole sequence
};

// An expression compiled twice: `forward` reads a path light to eye (x_0 first), `reverse` eye
// to light (the path tracer's camera walk). Both accept exactly the same paths.
//
// `join` matches a path split in two without reading it again: a light prefix P that takes
// `forward` to state f and a camera suffix Q whose reversal takes `reverse` to state r form a
// match PQ exactly when join(f, r). (A DFA state fixes every future of its prefix, so the
// verdict depends on (f, r) alone; compile_lpe fills the table from one representative per
// state.) BDPT runs each subpath through its automaton once per sample and decides each (s, t)
// connection with two steps and one lookup.
struct Lpe {
    std::string text;
    LpeDfa forward, reverse;
    bool uses_g = false;  // the expression mentions G, so its D means non-glossy only
    std::vector<uint8_t> join_table;  // forward states x reverse states, row-major
    bool join(uint8_t f, uint8_t r) const { return join_table[size_t(f) * reverse.next.size() + r] != 0; }
};
// Throws LpeError.
Lpe compile_lpe(std::string_view expr);

// AOV names: [A-Za-z_][A-Za-z0-9_]*, at most 64 characters. Throws std::invalid_argument naming
// the name and what is wrong.
void validate_aov_name(std::string_view name);

struct AovDesc {
    std::string name;
    std::string expr;
    bool operator==(const AovDesc&) const = default;
};

// "NAME=EXPR" (omega render --aov): name validated, expression compiled. Throws
// std::invalid_argument (LpeError for the expression).
AovDesc parse_aov_arg(std::string_view arg);
// Adds `aov`, or replaces the expression of the AOV of that name (the command line overrides
// the scene's film).
void set_aov(std::vector<AovDesc>& aovs, AovDesc aov);

// All AOVs of a film run as one automaton: a state is the tuple of every AOV's state, so a
// vertex costs one lookup whatever the number of AOVs, and `accept` says at once which AOVs
// match. Built by LpeSet when the reachable tuples are few (kMaxProductStates); `ok` false
// otherwise, and callers step each AOV's automaton instead.
constexpr size_t kMaxProductStates = 512;
struct LpeProduct {
    bool ok = false;
    uint16_t start = 0;
    std::vector<std::array<uint16_t, kVertexClasses>> next;
    std::vector<uint32_t> accept;     // bit i: AOV i accepts in this state
    std::vector<uint32_t> accept_l;   // bit i: AOV i accepts after one more L (next[s][L])
    uint16_t step(uint16_t s, VertexClass c) const { return next[s][size_t(c)]; }
};

// The AOVs of one film, compiled. Concurrency: immutable after construction; any thread.
class LpeSet {
public:
    LpeSet() = default;
    // Throws std::invalid_argument (LpeError for expressions; names and duplicates by name).
    explicit LpeSet(const std::vector<AovDesc>& aovs);
    size_t size() const { return lpes_.size(); }
    bool empty() const { return lpes_.empty(); }
    const Lpe& operator[](size_t i) const { return lpes_[i]; }
    const std::string& name(size_t i) const { return names_[i]; }
    // Bit i set: AOV i matches the full path (x_0 .. x_k, light first).
    uint32_t match(std::span<const VertexClass> path) const;

    // Every AOV's forward (light first) and reversed (eye first) automaton as one, and for a
    // light prefix in forward product state f and a camera suffix in reversed product state r,
    // the AOVs that match the joined path (Lpe::join of each component).
    const LpeProduct& forward_product() const { return forward_; }
    const LpeProduct& reverse_product() const { return reverse_; }
    bool has_products() const { return forward_.ok && reverse_.ok; }
    // Some expression mentions G. If none does, D and G behave alike in every automaton, so
    // callers may class every non-delta vertex D without asking the BSDF.
    bool uses_glossy() const { return uses_glossy_; }
    uint32_t join(uint16_t f, uint16_t r) const { return join_[size_t(f) * reverse_.next.size() + r]; }

private:
    std::vector<Lpe> lpes_;
    std::vector<std::string> names_;
    LpeProduct forward_, reverse_;
    std::vector<uint32_t> join_;
    bool uses_glossy_ = false;
};

}  // namespace omega
