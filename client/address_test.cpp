#include <gtest/gtest.h>

#include <map>

#include "address.h"
#include "client_error.h"

namespace omega::client {

TEST(Address, ParsesUnixAndTcp) {
    Address u = parse_address("unix:/run/omega/omegad.sock");
    EXPECT_EQ(u.kind, Address::Kind::unix_socket);
    EXPECT_EQ(u.path, "/run/omega/omegad.sock");
    EXPECT_EQ(u.text(), "unix:/run/omega/omegad.sock");

    Address t = parse_address("tcp:render-farm.local:7878");
    EXPECT_EQ(t.kind, Address::Kind::tcp);
    EXPECT_EQ(t.host, "render-farm.local");
    EXPECT_EQ(t.port, 7878);
    EXPECT_EQ(t.text(), "tcp:render-farm.local:7878");

    Address v6 = parse_address("tcp:[::1]:9000");
    EXPECT_EQ(v6.host, "::1");
    EXPECT_EQ(v6.port, 9000);
    EXPECT_EQ(v6.text(), "tcp:[::1]:9000");
}

TEST(Address, RefusesBadAddressesAsBadInput) {
    for (const char* bad : {"", "unix:", "tcp:host", "tcp::80", "tcp:host:0", "tcp:host:65536", "tcp:host:8x",
                            "tcp:::1:80", "http://x", "/run/omega/omegad.sock", "tcp:[::1]9000"}) {
        try {
            parse_address(bad);
            ADD_FAILURE() << "accepted '" << bad << "'";
        } catch (const ClientError& e) {
            EXPECT_EQ(e.exit_code(), kExitBadInput) << bad;
            EXPECT_NE(std::string(e.what()).find("bad daemon address"), std::string::npos) << e.what();
        }
    }
    EXPECT_THROW(parse_address("unix:/" + std::string(200, 'x')), ClientError);
}

TEST(Address, DefaultPrefersEnvThenRuntimeDirThenSystemSocket) {
    std::map<std::string, std::string> env;
    bool user_socket_exists = true;
    auto getenv_fn = [&](const char* n) -> const char* {
        auto it = env.find(n);
        return it == env.end() ? nullptr : it->second.c_str();
    };
    auto exists_fn = [&](const std::string& p) { return user_socket_exists && p == "/run/user/1000/omega/omegad.sock"; };

    EXPECT_EQ(default_address_text(getenv_fn, exists_fn), "unix:/run/omega/omegad.sock");
    env["XDG_RUNTIME_DIR"] = "/run/user/1000";
    EXPECT_EQ(default_address_text(getenv_fn, exists_fn), "unix:/run/user/1000/omega/omegad.sock");
    user_socket_exists = false;  // no per-user daemon: the system one
    EXPECT_EQ(default_address_text(getenv_fn, exists_fn), "unix:/run/omega/omegad.sock");
    env["OMEGA_HOST"] = "tcp:farm:7878";
    EXPECT_EQ(default_address_text(getenv_fn, exists_fn), "tcp:farm:7878");
    env["OMEGA_HOST"] = "";  // empty counts as unset
    EXPECT_EQ(default_address_text(getenv_fn, exists_fn), "unix:/run/omega/omegad.sock");
}

TEST(Address, ExplicitHostWinsOverDefault) {
    EXPECT_EQ(resolve_address(std::string("unix:/tmp/x.sock")).path, "/tmp/x.sock");
}

}  // namespace omega::client

#include "connection.h"

namespace omega::client {

TEST(Auth, MacMatchesTheProtocolTestVector) {
    std::string nonce;
    for (int i = 0; i < 16; ++i) nonce += "8f3a";
    EXPECT_EQ(auth_mac("s3cret", nonce, "alice"), "26b1d5bb85c36f62ee57db9aa7a7c24e7333efbaa9f211742be5491a046287df");
}

}  // namespace omega::client
