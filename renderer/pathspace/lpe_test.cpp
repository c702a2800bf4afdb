// The light path expression compiler: accept/reject tables over class strings, the reversed
// automaton agreeing with the forward one, parse errors naming the column, AOV names.
#include "pathspace/lpe.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace omega {
namespace {

std::vector<VertexClass> path(const std::string& letters) {
    std::vector<VertexClass> out;
    for (char c : letters) {
        switch (c) {
            case 'L': out.push_back(VertexClass::L); break;
            case 'E': out.push_back(VertexClass::E); break;
            case 'S': out.push_back(VertexClass::S); break;
            case 'D': out.push_back(VertexClass::D); break;
            case 'G': out.push_back(VertexClass::G); break;
            default: ADD_FAILURE() << "bad letter " << c;
        }
    }
    return out;
}

// Every string over the five classes up to length n (the reverse check enumerates them).
std::vector<std::string> all_strings(int n) {
    std::vector<std::string> out{""};
    size_t from = 0;
    for (int len = 1; len <= n; ++len) {
        const size_t to = out.size();
        for (size_t i = from; i < to; ++i)
            for (char c : std::string("LESDG")) {
                std::string next = out[i];
                next.push_back(c);
                out.push_back(std::move(next));
            }
        from = to;
    }
    return out;
}

bool matches(const Lpe& e, const std::string& s) { return e.forward.matches(path(s)); }

struct Case {
    const char* expr;
    std::vector<const char*> accept, reject;
};

TEST(Lpe, AcceptRejectTable) {
    const std::vector<Case> cases = {
        {"L D E", {"LDE", "LGE"}, {"LE", "LSE", "LDDE", "DE", "LD", "LDEE"}},
        {"L S+ D E", {"LSDE", "LSSDE", "LSSSGE"}, {"LDE", "LSE", "LSDDE", "LDSDE"}},
        {"L .* S .* E", {"LSE", "LDSE", "LSDE", "LDSDGE", "LSSE"}, {"LE", "LDE", "LDDGE"}},
        {"L D D+ E", {"LDDE", "LDGDE", "LGGGGE"}, {"LDE", "LDSDE", "LE"}},
        {"L (S|D)* E", {"LE", "LSE", "LDSDE"}, {"LLE", "LEE"}},
        {"L D? E", {"LE", "LDE"}, {"LDDE", "LSE"}},
        {"L .{2} E", {"LDDE", "LSDE"}, {"LDE", "LDDDE"}},
        {"L .{1,3} E", {"LDE", "LDDE", "LSSSE"}, {"LE", "LDDDDE"}},
        {"L .{2,} E", {"LDDE", "LDDDDDDDE"}, {"LE", "LDE"}},
        {"L .{,2} E", {"LE", "LDE", "LDDE"}, {"LDDDE"}},
        {"L (S D){2} E", {"LSDSDE"}, {"LSDE", "LSDSDSDE"}},
        {"L ( S | D S ) E", {"LSE", "LDSE"}, {"LDE", "LSSE"}},
        {"L.*GE", {"LGE", "LSDGE"}, {"LDE", "LSE"}},
        // With G mentioned, D means non-glossy only, so the two partition the non-delta vertices.
        {"L (S|G)* D E", {"LDE", "LGDE", "LSGDE"}, {"LGE", "LSE", "LDGE"}},
        // Without G, D is every non-delta vertex.
        {"L .* D E", {"LDE", "LGE", "LSGE"}, {"LSE"}},
        {"L D E | L G E", {"LDE", "LGE"}, {"LSE"}},
        {"L S* E", {"LE", "LSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSSE"}, {"LSDE"}},
        {"L(D|G)*E", {"LE", "LDGDGE"}, {"LDSE"}},
        {"((L))(((D)))E", {"LDE"}, {"LE"}},
        {"L S** E", {"LE", "LSSE"}, {"LDE"}},
        {"L (S*)+ E", {"LE", "LSSE"}, {"LDE"}},
    };
    for (const Case& c : cases) {
        const Lpe e = compile_lpe(c.expr);
        for (const char* a : c.accept) EXPECT_TRUE(matches(e, a)) << c.expr << " should accept " << a;
        for (const char* r : c.reject) EXPECT_FALSE(matches(e, r)) << c.expr << " should reject " << r;
    }
}

TEST(Lpe, ReverseAutomatonAcceptsTheReversedPaths) {
    const std::vector<std::string> strings = all_strings(6);
    for (const char* expr : {"L S+ D E", "L .* S .* E", "L D D+ E", "L (S D){2} E", "L .{1,3} G? E", "L (S|G D)* E",
                             "L D E | L S* E"}) {
        const Lpe e = compile_lpe(expr);
        for (const std::string& s : strings) {
            std::string r(s.rbegin(), s.rend());
            ASSERT_EQ(e.forward.matches(path(s)), e.reverse.matches(path(r))) << expr << " on " << s;
        }
    }
}

TEST(Lpe, PartitionIsExclusiveAndExhaustive) {
    // The partition the integration test renders: every path L x* E in exactly one of them.
    const Lpe a = compile_lpe("L D E"), b = compile_lpe("L D D+ E"), c = compile_lpe("L .* S .* E"),
              d = compile_lpe("L E");
    for (const std::string& inner : all_strings(6)) {
        if (inner.find_first_of("LE") != std::string::npos) continue;
        std::string s = "L";
        s.append(inner);
        s.push_back('E');
        const int n = int(matches(a, s)) + int(matches(b, s)) + int(matches(c, s)) + int(matches(d, s));
        EXPECT_EQ(n, 1) << s;
    }
}

TEST(Lpe, DeadStateIsAbsorbing) {
    const Lpe e = compile_lpe("L D E");
    EXPECT_FALSE(e.forward.accepts(0));
    for (int c = 0; c < kVertexClasses; ++c) EXPECT_EQ(e.forward.step(0, VertexClass(c)), 0);
    // A wrong first letter goes straight to the dead state.
    EXPECT_EQ(e.forward.step(e.forward.start, VertexClass::E), 0);
    EXPECT_LE(e.forward.next.size(), 8u);  // small: L, D, E, accept, dead
}

void expect_error(const char* expr, int column, const char* words) {
    try {
        compile_lpe(expr);
        ADD_FAILURE() << expr << " compiled";
    } catch (const LpeError& e) {
        EXPECT_EQ(e.column, column) << expr << ": " << e.what();
        EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(expr), std::string::npos) << e.what();
    }
}

TEST(Lpe, ParseErrorsNameTheColumn) {
    expect_error("L S+ ( E", 9, "expected ')'");
    expect_error("L X E", 3, "unknown symbol 'X'");
    expect_error("", 0, "empty");
    expect_error("   ", 0, "empty");
    expect_error("L D E)", 6, "')' without '('");
    expect_error("* L E", 1, "follows nothing");
}

TEST(Lpe, MoreParseErrors) {
    expect_error("L () E", 4, "empty group");
    expect_error("L D{ E", 6, "expected a number");
    expect_error("L D{2 E", 7, "expected '}'");
    expect_error("L D{3,1} E", 4, "below the minimum");
    expect_error("L D{99} E", 5, "bound above");
    expect_error("L D{0} E", 4, "empty sequence");
    expect_error("L | | E", 5, "expected a vertex class");
    expect_error("L (D|) E", 6, "expected a vertex class");
}

TEST(Lpe, TooComplexIsRefused) {
    // Nested bounds multiply: refused by size, not by hanging.
    EXPECT_THROW(compile_lpe("L ((((.{32}){32}){32}){32}) E"), LpeError);
}

TEST(Lpe, AovNames) {
    EXPECT_NO_THROW(validate_aov_name("caustics"));
    EXPECT_NO_THROW(validate_aov_name("_x9"));
    EXPECT_THROW(validate_aov_name(""), std::invalid_argument);
    EXPECT_THROW(validate_aov_name("9x"), std::invalid_argument);
    EXPECT_THROW(validate_aov_name("a.b"), std::invalid_argument);
    EXPECT_THROW(validate_aov_name("a b"), std::invalid_argument);
    EXPECT_THROW(validate_aov_name(std::string(65, 'a')), std::invalid_argument);
    EXPECT_THROW(LpeSet({{"a", "L D E"}, {"a", "L S E"}}), std::invalid_argument);
    EXPECT_THROW(LpeSet({{"ok", "L D E"}, {"bad", "L ( E"}}), LpeError);
    std::vector<AovDesc> many;
    for (int i = 0; i <= kMaxAovs; ++i) many.push_back({std::string(1, 'a').append(std::to_string(i)), "L D E"});
    EXPECT_THROW(LpeSet{many}, std::invalid_argument);
    LpeSet set({{"direct", "L D E"}, {"caustic", "L S+ D E"}, {"any", "L .* E"}});
    EXPECT_EQ(set.match(path("LDE")), 0b101u);
    EXPECT_EQ(set.match(path("LSDE")), 0b110u);
    EXPECT_EQ(set.match(path("LSE")), 0b100u);
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// The join table decides every split of every path exactly as reading the whole path would.
TEST(Lpe, JoinTableAgreesWithWholePathMatching) {
    const std::vector<std::string> strings = all_strings(4);
    for (const char* expr : {"L S+ D E", "L .* S .* E", "L D D+ E", "L (S D){2} E", "L .{1,3} G? E", "L D E | L S* E",
                             "L E"}) {
        const Lpe e = compile_lpe(expr);
        for (const std::string& p : strings)
            for (const std::string& q : strings) {
                uint8_t f = e.forward.start;
                for (VertexClass c : path(p)) f = e.forward.step(f, c);
                uint8_t r = e.reverse.start;
                const std::vector<VertexClass> qv = path(q);
                for (auto it = qv.rbegin(); it != qv.rend(); ++it) r = e.reverse.step(r, *it);
                std::string whole = p;
                whole.append(q);
                ASSERT_EQ(e.join(f, r), e.forward.matches(path(whole))) << expr << ": " << p << " | " << q;
            }
    }
}

}  // namespace
}  // namespace omega

namespace omega {
namespace {

// The product automata and their join table give, for every split of every path, the same
// matches as each AOV's own automata.
TEST(Lpe, ProductAgreesWithEachAutomaton) {
    const LpeSet set({{"a", "L S+ D E"}, {"b", "L .* S .* E"}, {"c", "L D D+ E"}, {"d", "L .{1,3} G? E"},
                      {"e", "L (S D){2} E"}, {"f", "L E"}});
    ASSERT_TRUE(set.has_products());
    const LpeProduct& fw = set.forward_product();
    const LpeProduct& rv = set.reverse_product();
    EXPECT_LT(fw.next.size(), 200u);
    const std::vector<std::string> strings = all_strings(4);
    for (const std::string& p : strings)
        for (const std::string& q : strings) {
            uint16_t f = fw.start;
            for (VertexClass c : path(p)) f = fw.step(f, c);
            uint16_t r = rv.start;
            const std::vector<VertexClass> qv = path(q);
            for (auto it = qv.rbegin(); it != qv.rend(); ++it) r = rv.step(r, *it);
            std::string whole = p;
            whole.append(q);
            const uint32_t want = set.match(path(whole));
            ASSERT_EQ(set.join(f, r), want) << p << " | " << q;
            if (q.empty()) {
                ASSERT_EQ(fw.accept[f], want) << p;
            }
            if (p.empty()) {
                ASSERT_EQ(rv.accept[r], want) << q;
            }
        }
}

}  // namespace
}  // namespace omega
