#include "daemon/checkpoint.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <cstring>
#include <fstream>

#include "daemon/asset_cache.h"
#include "daemon/config.h"
#include "daemon/listener.h"

namespace omega::daemon {
namespace {

std::string temp(const char* name) {
  return (std::filesystem::temp_directory_path() / (std::string("omegad-") + std::to_string(::getpid()) + "-" + name))
      .string();
}

TEST(Checkpoint, RoundTripsAndRejectsCorruption) {
  std::string p = temp("ck.bin");
  FilmSnapshot s;
  s.spp = 40;
  s.pass = 6;
  s.elapsed_s = 1.5;
  s.rel_error = 0.25;
  s.film = {1, 2, 3, 4, 5};
  write_checkpoint(p, s);
  auto r = read_checkpoint(p);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->spp, 40u);
  EXPECT_EQ(r->pass, 6u);
  EXPECT_EQ(*r->rel_error, 0.25);
  EXPECT_EQ(r->film, s.film);
  {
    std::fstream f(p, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(-1, std::ios::end);
    f.put('X');
  }
  EXPECT_THROW(read_checkpoint(p), std::runtime_error);
  std::filesystem::remove(p);
  EXPECT_FALSE(read_checkpoint(p));
}

TEST(Checkpoint, CarriesAovFilms) {
  std::string p = temp("ck-aov.bin");
  FilmSnapshot s;
  s.spp = 8;
  s.film = {1, 2, 3};
  write_checkpoint(p, s);
  // Without AOVs the layout is the one checkpoints always had: header, 7 fields, the film.
  EXPECT_EQ(std::filesystem::file_size(p), 8u + 8u + 8 + 8 + 8 + 8 + 1 + 8 + 8 + 3);
  s.aov_films = {{9, 8}, {}, {7, 7, 7, 7}};
  write_checkpoint(p, s);
  auto r = read_checkpoint(p);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->film, s.film);
  EXPECT_EQ(r->aov_films, s.aov_films);
  // A truncated AOV section is corrupt, not silently shorter (the checksum is recomputed here
  // to reach the parser: cut the last byte and fix the sum).
  std::string bytes;
  {
    std::ifstream in(p, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  bytes.pop_back();
  std::uint64_t h = 1469598103934665603ull;
  for (std::size_t i = 16; i < bytes.size(); ++i) h = (h ^ static_cast<unsigned char>(bytes[i])) * 1099511628211ull;
  std::memcpy(bytes.data() + 8, &h, sizeof h);
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
  EXPECT_THROW(read_checkpoint(p), std::runtime_error);
  std::filesystem::remove(p);
}

TEST(AssetCache, VerifiesHashesOnWriteAndRead) {
  std::string dir = temp("assets");
  std::filesystem::remove_all(dir);
  AssetCache c(dir);
  const std::string data = "v 0 0 0\n";
  const std::string sha = sha256_hex(data);
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_THROW(c.put(sha, "other"), std::runtime_error);
  EXPECT_FALSE(c.has(sha));
  c.put(sha, data);
  EXPECT_TRUE(c.has(sha));
  c.materialize(sha, data.size(), dir + "/out/a.obj");
  {
    std::ofstream f(c.path_of(sha), std::ios::trunc);
    f << "v 9 9 9\n";  // corrupted behind our back
  }
  EXPECT_THROW(c.materialize(sha, data.size(), dir + "/out/b.obj"), std::runtime_error);
  EXPECT_FALSE(c.has(sha));  // removed, so it will be asked for again
  std::filesystem::remove_all(dir);
}

TEST(Listener, RefusesNonLoopbackTcp) {
  EXPECT_EQ(parse_listen_address("tcp:127.0.0.1:7171").port, 7171);
  EXPECT_EQ(parse_listen_address("tcp:[::1]:80").host, "::1");
  EXPECT_EQ(parse_listen_address("unix:/run/x.sock").path, "/run/x.sock");
  EXPECT_FALSE(parse_listen_address("tcp:0.0.0.0:7171").loopback);  // the Server refuses it without auth
  EXPECT_FALSE(parse_listen_address("tcp:192.168.1.2:7171").loopback);
  EXPECT_TRUE(parse_listen_address("tcp:127.0.0.2:7171").loopback);
  EXPECT_EQ(parse_listen_address("tcp::7171").host, "127.0.0.1");
  EXPECT_THROW(parse_listen_address("tcp:127.0.0.1:99999"), std::invalid_argument);
  EXPECT_THROW(parse_listen_address("http://x"), std::invalid_argument);
}

TEST(Config, ReadsEveryKeyAndNamesTheBadOne) {
  std::string p = temp("cfg.yaml");
  {
    std::ofstream f(p);
    f << "listen: [unix:/tmp/x.sock]\nthreads: 3\nmax_running: 2\nallowed_roots: [/srv/assets]\nlog_level: warn\n"
         "auth_fail_limit: 5\n";
  }
  Config c = load_config(p);
  EXPECT_EQ(c.threads, 3);
  EXPECT_EQ(c.auth_fail_limit, 5);
  EXPECT_EQ(Config{}.auth_fail_limit, 10);  // the documented default
  {
    std::ofstream f(p);
    f << "auth_fail_limit: -1\n";
  }
  EXPECT_THROW(load_config(p), std::runtime_error);
  EXPECT_EQ(c.max_running, 2);
  EXPECT_EQ(c.allowed_roots.at(0), "/srv/assets");
  {
    std::ofstream f(p);
    f << "threads: 3\nmax_runing: 2\n";
  }
  try {
    load_config(p);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(":2: max_runing: unknown key"), std::string::npos) << e.what();
  }
  std::filesystem::remove(p);
}

}  // namespace
}  // namespace omega::daemon

namespace omega::daemon {
namespace {

// The breakdown's sums ride after the film (and the AOVs, if any), and read back as written;
// a checkpoint without them keeps its old layout.
TEST(Checkpoint, CarriesTheBreakdown) {
  std::string p = temp("ck-breakdown.bin");
  for (bool aovs : {false, true}) {
    FilmSnapshot s;
    s.spp = 8;
    s.film = {1, 2, 3};
    if (aovs) s.aov_films = {{9, 8}, {7}};
    s.breakdown_samples = "0:8";
    s.breakdown_state = "region image 6\nunits 3\nt 0 0 0\n";
    write_checkpoint(p, s);
    auto r = read_checkpoint(p);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->film, s.film);
    EXPECT_EQ(r->aov_films, s.aov_films);
    EXPECT_EQ(r->breakdown_samples, s.breakdown_samples);
    EXPECT_EQ(r->breakdown_state, s.breakdown_state);
    EXPECT_TRUE(r->breakdown.empty());  // the report is in memory only
  }
  std::filesystem::remove(p);
}

}  // namespace
}  // namespace omega::daemon
