// The job page's WebSocket messages (view_messages.h): what the browser may send, and the float
// tiles the page decodes.
#include "view_messages.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "shared_data.h"

#include <cmath>
#include <cstring>
#include <limits>

namespace omega::client {
namespace {

TEST(ViewMessages, DecodesEveryCommand) {
    auto c = decode_view_command(R"({"type": "login", "id": 1, "user": "alice", "token": "s3cret"})");
    ASSERT_TRUE(c) << c.message();
    EXPECT_EQ(c->kind, ViewCommandKind::login);
    EXPECT_EQ(c->user, "alice");
    EXPECT_EQ(c->token, "s3cret");
    c = decode_view_command(R"({"type": "set_priority", "id": 7, "job": 42, "priority": -3})");
    ASSERT_TRUE(c) << c.message();
    EXPECT_EQ(c->kind, ViewCommandKind::set_priority);
    EXPECT_EQ(c->id, 7u);
    EXPECT_EQ(c->job, 42u);
    EXPECT_EQ(c->priority, -3);
    for (const char* t : {"open", "cancel", "pause", "resume", "fetch"}) {
        auto r = decode_view_command(std::string(R"({"type": ")") + t + R"(", "id": 3, "job": 9})");
        ASSERT_TRUE(r) << t << ": " << r.message();
        EXPECT_EQ(to_string(r->kind), t);
        EXPECT_EQ(r->job, 9u);
    }
    EXPECT_TRUE(decode_view_command(R"({"type": "list", "id": 2})"));
    EXPECT_TRUE(decode_view_command(R"({"type": "close", "id": 2})"));
}

TEST(ViewMessages, RefusesMalformedInputNamingTheField) {
    struct Case {
        std::string text, needle;
    };
    const Case cases[] = {
        {"", "not a JSON object"},
        {"[1, 2]", "not a JSON object"},
        {"{\"type\": \"open\", \"id\": 1}", "job"},
        {"{\"type\": \"open\", \"id\": 1, \"job\": \"7\"}", "job"},
        {"{\"type\": \"open\", \"id\": 1, \"job\": -1}", "job"},
        {"{\"type\": \"set_priority\", \"id\": 1, \"job\": 1, \"priority\": 1001}", "priority"},
        {"{\"type\": \"shutdown\", \"id\": 1}", "unknown message type"},
        {"{\"type\": \"list\"}", "id"},
        {"{\"type\": \"list\", \"id\": 1, \"id\": 2}", "repeats"},
        {"{\"type\": \"login\", \"id\": 1, \"user\": \"a\"}", "token"},
        {"{\"type\": \"login\", \"id\": 1, \"user\": \"a\", \"token\": [1]}", "token"},
        {"{\"type\": \"list\", \"id\": 1,", "not JSON"},
        {std::string("{\"type\": \"list\", \"id\": 1, \"x\": \"\xff\"}"), "UTF-8"},
        {"{\"type\": \"login\", \"id\": 1, \"user\": \"a\", \"token\": \"" + std::string(5000, 'x') + "\"}", "4096"},
        {std::string(3000, '[') + std::string(3000, ']'), ""},
        {"{\"type\": \"login\", \"id\": 1, \"user\": \"a\\u0085b\", \"token\": \"t\"}", "user: not printable"},
        {"{\"type\": \"login\", \"id\": 1, \"user\": \"a\", \"token\": \"t\\u0000\"}", "token: not printable"},
    };
    for (const auto& c : cases) {
        auto r = decode_view_command(c.text);
        ASSERT_FALSE(r) << c.text.substr(0, 80);
        EXPECT_NE(r.message().find(c.needle), std::string::npos) << r.message();
    }
}

TEST(ViewMessages, CommandsRoundTrip) {
    ViewCommand c;
    c.kind = ViewCommandKind::login;
    c.id = 12;
    c.user = "bj\xc3\xb6rk";
    c.token = "a\"b\\c: [x], {y}";
    auto r = decode_view_command(encode_view_command(c));
    ASSERT_TRUE(r) << r.message();
    EXPECT_EQ(r->user, c.user);
    EXPECT_EQ(r->token, c.token);
}

// Every input the fuzzer once failed on (fuzz/regressions/view_messages/): refused, or decoded
// to a command whose own encoding decodes to the same command.
TEST(ViewMessages, FuzzerFindingsRoundTripOrAreRefused) {
    const auto dir = std::filesystem::path(omega::test::source_dir()) / "fuzz/regressions/view_messages";
    int n = 0;
    for (const auto& f : std::filesystem::directory_iterator(dir)) {
        std::ifstream in(f.path(), std::ios::binary);
        const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        ++n;
        auto c = decode_view_command(text);
        if (!c) continue;
        auto again = decode_view_command(encode_view_command(*c));
        ASSERT_TRUE(again) << f.path() << ": " << again.message() << "\nfrom: " << encode_view_command(*c);
        EXPECT_EQ(again->kind, c->kind) << f.path();
        EXPECT_EQ(again->user, c->user) << f.path();
        EXPECT_EQ(again->token, c->token) << f.path();
    }
    EXPECT_GE(n, 2);
}

TEST(ViewMessages, FloatTileLayoutAndNoNaN) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
    std::vector<float> rgb = {1.5f, nan, 2.f, -inf, 0.25f, 3.f};  // 2 x 1 pixels
    std::vector<float> var = {0.1f, 0.2f, 0.3f, 0.4f, inf, 0.6f};
    FloatTile t{.job = 0x0102030405060708ull, .x0 = 4, .y0 = 6, .x1 = 6, .y1 = 7, .film_width = 8, .film_height = 9,
                .pass = 3, .spp = 12, .rgb = rgb, .var = var};
    const std::string b = pack_float_tile(t);
    ASSERT_EQ(b.size(), kTileHeaderBytes + 4 * 12);
    EXPECT_EQ(b.substr(0, 4), "OTF1");
    auto u32 = [&](size_t o) {
        uint32_t v;
        std::memcpy(&v, b.data() + o, 4);  // the test host is little-endian, like the wire
        return v;
    };
    auto f32 = [&](size_t i) {
        float v;
        std::memcpy(&v, b.data() + kTileHeaderBytes + 4 * i, 4);
        return v;
    };
    EXPECT_EQ(u32(4), 1u);
    EXPECT_EQ(u32(8), 0x05060708u);
    EXPECT_EQ(u32(12), 0x01020304u);
    EXPECT_EQ(u32(16), 4u);
    EXPECT_EQ(u32(28), 7u);
    EXPECT_EQ(u32(32), 8u);
    EXPECT_EQ(u32(36), 9u);
    EXPECT_EQ(u32(40), 3u);
    EXPECT_EQ(u32(44), 12u);
    EXPECT_EQ(f32(0), 1.5f);
    EXPECT_EQ(f32(1), 0.f);  // NaN
    EXPECT_EQ(f32(3), 0.f);  // -inf
    EXPECT_EQ(f32(5), 3.f);
    EXPECT_EQ(f32(6), 0.1f);
    EXPECT_EQ(f32(10), 0.f);  // inf variance
    for (size_t i = 0; i < 12; ++i) EXPECT_TRUE(std::isfinite(f32(i)));
    t.rgb = std::span(rgb).subspan(0, 3);
    EXPECT_THROW(pack_float_tile(t), std::invalid_argument);
    const std::string e = pack_exr(5, "EXRDATA");
    EXPECT_EQ(e.substr(0, 4), "OEXR");
    EXPECT_EQ(e.substr(16), "EXRDATA");
}

TEST(ViewMessages, JobListCarriesTheListColumnsAndOwnership) {
    protocol::JobInfo a;
    a.job = 3;
    a.name = "cornell";
    a.owner = "alice";
    a.state = protocol::JobState::running;
    a.halt.spp = 64;
    a.progress.spp = 12;
    protocol::JobInfo b = a;
    b.job = 4;
    b.owner = "bob";
    const std::string s = view_jobs(0, "alice", {a, b});
    EXPECT_NE(s.find(R"("job": 3, "name": "cornell", "state": "running")"), std::string::npos) << s;
    EXPECT_NE(s.find(R"("label": "cornell", "progress_text": "12/64 spp)"), std::string::npos) << s;
    EXPECT_NE(s.find(R"("mine": 1}, {"job": 4)"), std::string::npos) << s;
    EXPECT_NE(s.find(R"("mine": 0})"), std::string::npos) << s;
}

TEST(ViewMessages, WebSocketUpgradeOnlyFromThePageOnLoopback) {
    EXPECT_TRUE(websocket_upgrade_allowed("127.0.0.1:7180", nullptr));
    EXPECT_TRUE(websocket_upgrade_allowed("127.0.0.1:7180", "http://127.0.0.1:7180"));
    EXPECT_TRUE(websocket_upgrade_allowed("localhost:7180", "http://localhost:7180"));
    EXPECT_TRUE(websocket_upgrade_allowed("[::1]:7180", "http://[::1]:7180"));
    EXPECT_TRUE(websocket_upgrade_allowed("127.1.2.3", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed(nullptr, nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("127.0.0.1:7180", "http://evil.example"));
    EXPECT_FALSE(websocket_upgrade_allowed("127.0.0.1:7180", "http://127.0.0.1:7181"));
    EXPECT_FALSE(websocket_upgrade_allowed("evil.example:7180", "http://evil.example:7180"));  // DNS rebinding
    EXPECT_FALSE(websocket_upgrade_allowed("128.0.0.1:7180", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("[::2]:7180", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("[::1", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("[::1]x", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("", nullptr));
    // Found by fuzz_view_messages: brackets around a name, and a port that is not a number.
    EXPECT_FALSE(websocket_upgrade_allowed("[localhost]:81", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("[127.0.0.1]", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("localhost:81\xef\xbb\xbf" "81", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("localhost:", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("localhost:65536", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("127.0.0.1:7180:1", nullptr));
    EXPECT_FALSE(websocket_upgrade_allowed("::1", nullptr));  // unbracketed v6 has no port syntax
    EXPECT_TRUE(websocket_upgrade_allowed("localhost:65535", nullptr));
    EXPECT_TRUE(websocket_upgrade_allowed("[::1]", "http://[::1]"));
    EXPECT_TRUE(is_loopback_host("::1"));
    EXPECT_FALSE(is_loopback_host("0.0.0.0"));
}

}  // namespace
}  // namespace omega::client
