#include "pathspace/lpe.h"

#include <algorithm>
#include <map>
#include <memory>

namespace omega {

namespace {

constexpr uint8_t bit(VertexClass c) { return uint8_t(1u << unsigned(c)); }
constexpr uint8_t kAny = 0x1f;
constexpr size_t kMaxNfaStates = 1 << 16;

// Parse tree. Built once per expression on the thread that parses the scene or the command line.
struct Node {
    enum Kind { Sym, Cat, Alt, Rep } kind = Sym;
    uint8_t mask = 0;         // Sym: the classes it matches
    std::vector<std::unique_ptr<Node>> kids;
    int min = 0, max = -1;    // Rep: bounds, max -1 unbounded
};

class Parser {
public:
    Parser(std::string_view text, bool uses_g) : s_(text), uses_g_(uses_g) {}

    std::unique_ptr<Node> parse() {
        skip();
        if (i_ >= s_.size()) fail(0, "the expression is empty");
        auto n = alternation();
        skip();
        if (i_ < s_.size()) fail(i_ + 1, s_[i_] == ')' ? "')' without '('" : "unexpected '" + std::string(1, s_[i_]) + "'");
        return n;
    }

private:
    [[noreturn]] void fail(size_t column, const std::string& why) const { throw LpeError(std::string(s_), int(column), why); }
    void skip() {
        while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t')) ++i_;
    }
    bool at(char c) {
        skip();
        return i_ < s_.size() && s_[i_] == c;
    }

    std::unique_ptr<Node> alternation() {
        auto first = concatenation();
        if (!at('|')) return first;
        auto alt = std::make_unique<Node>();
        alt->kind = Node::Alt;
        alt->kids.push_back(std::move(first));
        while (at('|')) {
            ++i_;
            alt->kids.push_back(concatenation());
        }
        return alt;
    }

    std::unique_ptr<Node> concatenation() {
        auto cat = std::make_unique<Node>();
        cat->kind = Node::Cat;
        for (;;) {
            skip();
            if (i_ >= s_.size() || s_[i_] == '|' || s_[i_] == ')') break;
            cat->kids.push_back(postfix());
        }
        if (cat->kids.empty()) {
            skip();
            fail(i_ + 1, i_ < s_.size() ? "expected a vertex class (L, E, S, D, G, '.') or '(' before '" +
                                              std::string(1, s_[i_]) + "'"
                                        : "expected a vertex class (L, E, S, D, G, '.') or '(' at the end");
        }
        if (cat->kids.size() == 1) return std::move(cat->kids.front());
        return cat;
    }

    std::unique_ptr<Node> postfix() {
        auto n = atom();
        for (;;) {
            skip();
            if (i_ >= s_.size()) return n;
            const char c = s_[i_];
            int lo, hi;
            if (c == '*') lo = 0, hi = -1, ++i_;
            else if (c == '+') lo = 1, hi = -1, ++i_;
            else if (c == '?') lo = 0, hi = 1, ++i_;
            else if (c == '{') bounds(lo, hi);
            else return n;
            auto rep = std::make_unique<Node>();
            rep->kind = Node::Rep;
            rep->min = lo;
            rep->max = hi;
            rep->kids.push_back(std::move(n));
            n = std::move(rep);
        }
    }

    // {n} {n,m} {n,} {,m}
    void bounds(int& lo, int& hi) {
        const size_t open = i_++;
        auto number = [&](int& out) {
            skip();
            const size_t b = i_;
            long v = 0;
            while (i_ < s_.size() && s_[i_] >= '0' && s_[i_] <= '9') {
                v = v * 10 + (s_[i_] - '0');
                if (v > kMaxBound) fail(b + 1, "bound above " + std::to_string(kMaxBound));
                ++i_;
            }
            out = int(v);
            return i_ > b;
        };
        int a = 0, b = -1;
        const bool has_a = number(a);
        skip();
        if (at(',')) {
            ++i_;
            if (!number(b)) b = -1;
            else if (b < a) fail(open + 1, "bound {" + std::to_string(a) + "," + std::to_string(b) + "}: the maximum is below the minimum");
            if (!has_a) a = 0;
        } else {
            if (!has_a) fail(i_ + 1, "expected a number in '{'");
            b = a;
        }
        if (!at('}')) fail(i_ + 1, "expected '}' to close the '{' at column " + std::to_string(open + 1));
        ++i_;
        if (b == 0) fail(open + 1, "bound {0}: matches only the empty sequence; leave the term out");
        lo = a;
        hi = b;
    }

    std::unique_ptr<Node> atom() {
        skip();
        const size_t at_col = i_ + 1;
        const char c = s_[i_];
        auto sym = [&](uint8_t mask) {
            ++i_;
            auto n = std::make_unique<Node>();
            n->mask = mask;
            return n;
        };
        switch (c) {
            case 'L': return sym(bit(VertexClass::L));
            case 'E': return sym(bit(VertexClass::E));
            case 'S': return sym(bit(VertexClass::S));
            case 'G': return sym(bit(VertexClass::G));
            case 'D': return sym(uses_g_ ? bit(VertexClass::D) : uint8_t(bit(VertexClass::D) | bit(VertexClass::G)));
            case '.': return sym(kAny);
            case '(': {
                ++i_;
                skip();
                if (at(')')) fail(i_ + 1, "empty group '()'");
                auto n = alternation();
                if (!at(')')) fail(i_ + 1, "expected ')' to close the '(' at column " + std::to_string(at_col));
                ++i_;
                return n;
            }
            case '*': case '+': case '?': case '{':
                fail(at_col, std::string("'") + c + "' follows nothing it could repeat");
            default:
                fail(at_col, std::string("unknown symbol '") + c + "' (vertex classes are L, E, S, D, G and '.')");
        }
    }

    std::string_view s_;
    bool uses_g_;
    size_t i_ = 0;
};

// Thompson NFA: each state has epsilon edges and at most one class-set edge.
struct Nfa {
    struct State {
        uint8_t mask = 0;
        int out = -1;
        std::vector<int> eps;
    };
    std::vector<State> st;
    const std::string* text;

    int add() {
        if (st.size() >= kMaxNfaStates) throw LpeError(*text, 0, "too large (nested bounds repeat it too often)");
        st.emplace_back();
        return int(st.size()) - 1;
    }
    struct Frag {
        int in, out;
    };
    // `reversed`: concatenations read right to left (the expression of the reversed paths).
    Frag build(const Node& n, bool reversed) {
        switch (n.kind) {
            case Node::Sym: {
                int a = add(), b = add();
                st[size_t(a)].mask = n.mask;
                st[size_t(a)].out = b;
                return {a, b};
            }
            case Node::Cat: {
                const size_t m = n.kids.size();
                Frag f = build(*n.kids[reversed ? m - 1 : 0], reversed);
                for (size_t j = 1; j < m; ++j) {
                    Frag g = build(*n.kids[reversed ? m - 1 - j : j], reversed);
                    st[size_t(f.out)].eps.push_back(g.in);
                    f.out = g.out;
                }
                return f;
            }
            case Node::Alt: {
                int a = add(), b = add();
                for (const auto& k : n.kids) {
                    Frag g = build(*k, reversed);
                    st[size_t(a)].eps.push_back(g.in);
                    st[size_t(g.out)].eps.push_back(b);
                }
                return {a, b};
            }
            case Node::Rep: {
                int a = add();
                int cur = a;
                for (int j = 0; j < n.min; ++j) {
                    Frag g = build(*n.kids[0], reversed);
                    st[size_t(cur)].eps.push_back(g.in);
                    cur = g.out;
                }
                int b = add();
                if (n.max < 0) {
                    // Kleene star after the required copies.
                    Frag g = build(*n.kids[0], reversed);
                    st[size_t(cur)].eps.push_back(g.in);
                    st[size_t(g.out)].eps.push_back(g.in);
                    st[size_t(g.out)].eps.push_back(b);
                    st[size_t(cur)].eps.push_back(b);
                } else {
                    for (int j = n.min; j < n.max; ++j) {
                        Frag g = build(*n.kids[0], reversed);
                        st[size_t(cur)].eps.push_back(g.in);
                        st[size_t(cur)].eps.push_back(b);  // stop here
                        cur = g.out;
                    }
                    st[size_t(cur)].eps.push_back(b);
                }
                return {a, b};
            }
        }
        return {-1, -1};
    }

    void closure(std::vector<int>& set) const {
        std::vector<int> stack = set;
        std::vector<char> in(st.size(), 0);
        for (int s : set) in[size_t(s)] = 1;
        while (!stack.empty()) {
            int s = stack.back();
            stack.pop_back();
            for (int e : st[size_t(s)].eps)
                if (!in[size_t(e)]) {
                    in[size_t(e)] = 1;
                    set.push_back(e);
                    stack.push_back(e);
                }
        }
        std::sort(set.begin(), set.end());
    }
};

// Subset construction. State 0 is the dead state (the empty set).
LpeDfa determinize(const Node& root, bool reversed, const std::string& text) {
    Nfa nfa;
    nfa.text = &text;
    Nfa::Frag f = nfa.build(root, reversed);
    LpeDfa dfa;
    std::map<std::vector<int>, uint8_t> ids;
    std::vector<std::vector<int>> sets;
    auto intern = [&](std::vector<int> set) -> uint8_t {
        if (set.empty()) return 0;
        nfa.closure(set);
        auto it = ids.find(set);
        if (it != ids.end()) return it->second;
        if (sets.size() >= size_t(kMaxDfaStates) + 1)
            throw LpeError(text, 0, "too complex (its automaton needs more than " + std::to_string(kMaxDfaStates) + " states)");
        const uint8_t id = uint8_t(sets.size());
        ids.emplace(set, id);
        sets.push_back(std::move(set));
        return id;
    };
    sets.push_back({});  // dead
    dfa.start = intern({f.in});
    for (size_t d = 0; d < sets.size(); ++d) {
        std::array<uint8_t, kVertexClasses> row{};
        for (int c = 0; c < kVertexClasses; ++c) {
            std::vector<int> to;
            for (int s : sets[d]) {
                const auto& ns = nfa.st[size_t(s)];
                if (ns.out >= 0 && (ns.mask >> c & 1)) to.push_back(ns.out);
            }
            std::sort(to.begin(), to.end());
            to.erase(std::unique(to.begin(), to.end()), to.end());
            row[size_t(c)] = intern(std::move(to));
        }
        dfa.next.push_back(row);
        dfa.accept.push_back(std::binary_search(sets[d].begin(), sets[d].end(), f.out) ? 1 : 0);
    }
    return dfa;
}

// For each state reachable from `start`, the shortest string reaching it (read in the
// automaton's own order); unreachable states keep nothing and are marked in `reached`.
void representatives(const LpeDfa& dfa, std::vector<std::vector<VertexClass>>& rep, std::vector<char>& reached) {
    rep.assign(dfa.next.size(), {});
    reached.assign(dfa.next.size(), 0);
    std::vector<uint8_t> queue{dfa.start};
    reached[dfa.start] = 1;
    for (size_t i = 0; i < queue.size(); ++i) {
        const uint8_t q = queue[i];
        for (int c = 0; c < kVertexClasses; ++c) {
            const uint8_t n = dfa.step(q, VertexClass(c));
            if (reached[n]) continue;
            reached[n] = 1;
            rep[n] = rep[q];
            rep[n].push_back(VertexClass(c));
            queue.push_back(n);
        }
    }
}

std::vector<uint8_t> join_table(const LpeDfa& forward, const LpeDfa& reverse) {
    std::vector<std::vector<VertexClass>> fr, rr;
    std::vector<char> fok, rok;
    representatives(forward, fr, fok);
    representatives(reverse, rr, rok);
    const size_t nf = forward.next.size(), nr = reverse.next.size();
    std::vector<uint8_t> table(nf * nr, 0);
    for (size_t f = 1; f < nf; ++f) {
        if (!fok[f]) continue;
        for (size_t r = 1; r < nr; ++r) {
            if (!rok[r]) continue;
            // rr[r] is the suffix read eye first: run it light first from f.
            uint8_t q = uint8_t(f);
            for (auto it = rr[r].rbegin(); it != rr[r].rend() && q; ++it) q = forward.step(q, *it);
            table[f * nr + r] = forward.accepts(q) ? 1 : 0;
        }
    }
    return table;
}

// Breadth-first over the tuples of component states reachable from the tuple of starts.
// `tuples` receives each product state's components (n per state).
LpeProduct make_product(const std::vector<const LpeDfa*>& dfas, std::vector<uint8_t>& tuples) {
    LpeProduct p;
    const size_t n = dfas.size();
    // Keys widened to uint16_t: GCC 12 warns (falsely) on the memcmp a byte-vector key compiles to.
    std::map<std::vector<uint16_t>, uint16_t> ids;
    tuples.clear();
    auto intern = [&](const std::vector<uint16_t>& t) -> int {
        auto it = ids.find(t);
        if (it != ids.end()) return it->second;
        if (ids.size() >= kMaxProductStates) return -1;
        const uint16_t id = uint16_t(ids.size());
        ids.emplace(t, id);
        for (uint16_t v : t) tuples.push_back(uint8_t(v));
        return id;
    };
    std::vector<uint16_t> t(n);
    for (size_t a = 0; a < n; ++a) t[a] = dfas[a]->start;
    p.start = uint16_t(intern(t));
    for (size_t s = 0; s < ids.size(); ++s) {
        std::array<uint16_t, kVertexClasses> row{};
        uint32_t acc = 0;
        for (size_t a = 0; a < n; ++a)
            if (dfas[a]->accepts(tuples[s * n + a])) acc |= 1u << a;
        for (int c = 0; c < kVertexClasses; ++c) {
            for (size_t a = 0; a < n; ++a) t[a] = dfas[a]->step(tuples[s * n + a], VertexClass(c));
            const int id = intern(t);
            if (id < 0) return LpeProduct{};  // too many: not ok
            row[size_t(c)] = uint16_t(id);
        }
        p.next.push_back(row);
        p.accept.push_back(acc);
    }
    for (size_t s = 0; s < p.next.size(); ++s) p.accept_l.push_back(p.accept[p.step(uint16_t(s), VertexClass::L)]);
    p.ok = true;
    return p;
}

}  // namespace

char vertex_class_letter(VertexClass c) { return "LESDG"[size_t(c)]; }

LpeError::LpeError(const std::string& e, int col, const std::string& why)
    : std::invalid_argument("aov expression '" + e + "'" + (col > 0 ? ": column " + std::to_string(col) : std::string()) +
                            ": " + why),
      expr(e),
      column(col) {}

bool LpeDfa::matches(std::span<const VertexClass> path) const {
    uint8_t s = start;
    for (VertexClass c : path) s = step(s, c);
    return accepts(s);
}

Lpe compile_lpe(std::string_view expr) {
    Lpe out;
    out.text = std::string(expr);
    out.uses_g = expr.find('G') != std::string_view::npos;
    auto root = Parser(expr, out.uses_g).parse();
    out.forward = determinize(*root, false, out.text);
    out.reverse = determinize(*root, true, out.text);
    out.join_table = join_table(out.forward, out.reverse);
    return out;
}

void validate_aov_name(std::string_view name) {
    auto bad = [&](const std::string& why) {
        return std::invalid_argument("aov name '" + std::string(name) + "': " + why);
    };
    if (name.empty()) throw std::invalid_argument("aov name is empty");
    if (name.size() > 64) throw bad("longer than 64 characters");
    const char c0 = name[0];
    if (!((c0 >= 'A' && c0 <= 'Z') || (c0 >= 'a' && c0 <= 'z') || c0 == '_'))
        throw bad("must start with a letter or '_'");
    for (char c : name)
        if (!((c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'))
            throw bad("only letters, digits and '_' are allowed (it names EXR channels aov.NAME.R)");
}

AovDesc parse_aov_arg(std::string_view arg) {
    const size_t eq = arg.find('=');
    if (eq == std::string_view::npos)
        throw std::invalid_argument("--aov '" + std::string(arg) + "': expected NAME=EXPR, e.g. caustics='L S+ D E'");
    AovDesc a{std::string(arg.substr(0, eq)), std::string(arg.substr(eq + 1))};
    validate_aov_name(a.name);
    compile_lpe(a.expr);
    return a;
}

void set_aov(std::vector<AovDesc>& aovs, AovDesc aov) {
    for (AovDesc& a : aovs)
        if (a.name == aov.name) {
            a.expr = std::move(aov.expr);
            return;
        }
    aovs.push_back(std::move(aov));
}

LpeSet::LpeSet(const std::vector<AovDesc>& aovs) {
    if (aovs.size() > size_t(kMaxAovs))
        throw std::invalid_argument("at most " + std::to_string(kMaxAovs) + " aovs per film, " + std::to_string(aovs.size()) +
                                    " given");
    for (const AovDesc& a : aovs) {
        validate_aov_name(a.name);
        if (std::find(names_.begin(), names_.end(), a.name) != names_.end())
            throw std::invalid_argument("aov '" + a.name + "' is defined twice");
        lpes_.push_back(compile_lpe(a.expr));
        names_.push_back(a.name);
        uses_glossy_ = uses_glossy_ || lpes_.back().uses_g;
    }
    std::vector<const LpeDfa*> fw, rv;
    for (const Lpe& e : lpes_) {
        fw.push_back(&e.forward);
        rv.push_back(&e.reverse);
    }
    std::vector<uint8_t> ft, rt;
    forward_ = make_product(fw, ft);
    reverse_ = make_product(rv, rt);
    if (!has_products()) return;
    const size_t n = lpes_.size(), nf = forward_.next.size(), nr = reverse_.next.size();
    join_.assign(nf * nr, 0);
    for (size_t f = 0; f < nf; ++f)
        for (size_t r = 0; r < nr; ++r) {
            uint32_t m = 0;
            for (size_t a = 0; a < n; ++a) {
                const uint8_t fa = ft[f * n + a], ra = rt[r * n + a];
                if (fa && ra && lpes_[a].join(fa, ra)) m |= 1u << a;
            }
            join_[f * nr + r] = m;
        }
}

uint32_t LpeSet::match(std::span<const VertexClass> path) const {
    uint32_t mask = 0;
    for (size_t i = 0; i < lpes_.size(); ++i)
        if (lpes_[i].forward.matches(path)) mask |= 1u << i;
    return mask;
}

}  // namespace omega
