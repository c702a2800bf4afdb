#include "daemon/tcp_auth.h"

#include <gtest/gtest.h>

#include <string>

namespace omega::daemon {
namespace {

std::string nonce8f3a() {
  std::string n;
  for (int i = 0; i < 16; ++i) n += "8f3a";
  return n;
}

TEST(TcpAuth, MatchesTheProtocolTestVector) {
  EXPECT_EQ(expected_mac("s3cret", nonce8f3a(), "alice"),
            "26b1d5bb85c36f62ee57db9aa7a7c24e7333efbaa9f211742be5491a046287df");
}

TEST(TcpAuth, AcceptsOnlyTheRightUserAndMac) {
  std::map<std::string, std::string> users{{"alice", "s3cret"}};
  const std::string mac = expected_mac("s3cret", nonce8f3a(), "alice");
  EXPECT_TRUE(check_auth(users, nonce8f3a(), "alice", mac));
  EXPECT_FALSE(check_auth(users, nonce8f3a(), "bob", mac));
  EXPECT_FALSE(check_auth(users, nonce8f3a(), "alice", std::string(64, '0')));
  EXPECT_FALSE(check_auth(users, make_nonce(), "alice", mac));  // a replay under another nonce
  EXPECT_FALSE(check_auth({}, nonce8f3a(), "alice", mac));
}

TEST(TcpAuth, NoncesAreFreshHex) {
  std::string a = make_nonce(), b = make_nonce();
  EXPECT_EQ(a.size(), 64u);
  EXPECT_NE(a, b);
  EXPECT_EQ(a.find_first_not_of("0123456789abcdef"), std::string::npos);
}

}  // namespace
}  // namespace omega::daemon
