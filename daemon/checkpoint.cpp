#include "daemon/checkpoint.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace omega::daemon {

namespace {

constexpr char kMagic[8] = {'O', 'M', 'G', 'C', 'K', 'P', 'T', '1'};
// Starts the optional breakdown section ("BDK1"): no AOV count (1 to 32) can equal it.
constexpr std::uint32_t kBreakdownTag = 0x314b4442;

[[noreturn]] void io_fail(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what + ": " + std::strerror(errno));
}

std::uint64_t fnv1a(std::string_view d) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : d) h = (h ^ c) * 1099511628211ull;
  return h;
}

template <class T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);  // the host is little-endian (x86-64, arm64)
}
template <class T>
T get(std::string_view& s) {
  if (s.size() < sizeof(T)) throw std::runtime_error("truncated");
  T v;
  std::memcpy(&v, s.data(), sizeof v);
  s.remove_prefix(sizeof v);
  return v;
}

}  // namespace

void write_file_atomic(const std::string& path, std::string_view data) {
  std::string tmp = path + ".tmp";
  int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd < 0) io_fail(tmp, "open");
  std::size_t done = 0;
  while (done < data.size()) {
    ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      int e = errno;
      ::close(fd);
      ::unlink(tmp.c_str());  // a full disk must not stay full because of our half-written file
      errno = e;
      io_fail(tmp, "write");
    }
    done += std::size_t(n);
  }
  if (::fsync(fd) < 0) {
    int e = errno;
    ::close(fd);
    ::unlink(tmp.c_str());
    errno = e;
    io_fail(tmp, "fsync");
  }
  ::close(fd);
  if (::rename(tmp.c_str(), path.c_str()) < 0) {
    int e = errno;
    ::unlink(tmp.c_str());
    errno = e;
    io_fail(path, "rename");
  }
  std::string dir = std::filesystem::path(path).parent_path().string();
  int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw std::runtime_error(path + ": read error");
  return s;
}

void write_checkpoint(const std::string& path, const FilmSnapshot& s) {
  std::string body;
  body.reserve(s.film.size() + 64);
  put(body, s.spp);
  put(body, s.pass);
  put(body, s.elapsed_s);
  put(body, s.nonfinite);
  put(body, std::uint8_t(s.rel_error.has_value()));
  put(body, s.rel_error.value_or(0.0));
  put(body, std::uint64_t(s.film.size()));
  body.append(reinterpret_cast<const char*>(s.film.data()), s.film.size());
  // Optional AOV section after the film: a count, then each film's size and bytes.
  if (!s.aov_films.empty()) {
    put(body, std::uint32_t(s.aov_films.size()));
    for (const auto& f : s.aov_films) {
      put(body, std::uint64_t(f.size()));
      body.append(reinterpret_cast<const char*>(f.data()), f.size());
    }
  }
  // Optional breakdown section, last: a tag no AOV count can equal, then the two strings.
  if (!s.breakdown_state.empty()) {
    put(body, kBreakdownTag);
    for (const std::string* t : {&s.breakdown_samples, &s.breakdown_state}) {
      put(body, std::uint64_t(t->size()));
      body += *t;
    }
  }
  std::string file(kMagic, sizeof kMagic);
  put(file, fnv1a(body));
  file += body;
  write_file_atomic(path, file);
}

std::optional<FilmSnapshot> read_checkpoint(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return std::nullopt;
  std::string file = read_file(path);
  try {
    std::string_view v(file);
    if (v.size() < sizeof kMagic || std::memcmp(v.data(), kMagic, sizeof kMagic) != 0)
      throw std::runtime_error("not a checkpoint (bad magic)");
    v.remove_prefix(sizeof kMagic);
    auto sum = get<std::uint64_t>(v);
    if (fnv1a(v) != sum) throw std::runtime_error("checksum mismatch");
    FilmSnapshot s;
    s.spp = get<std::uint64_t>(v);
    s.pass = get<std::uint64_t>(v);
    s.elapsed_s = get<double>(v);
    s.nonfinite = get<std::uint64_t>(v);
    bool has_err = get<std::uint8_t>(v) != 0;
    double err = get<double>(v);
    if (has_err) s.rel_error = err;
    auto n = get<std::uint64_t>(v);
    if (n > v.size()) throw std::runtime_error("truncated film");
    s.film.assign(v.begin(), v.begin() + std::ptrdiff_t(n));
    v.remove_prefix(n);
    auto peek_tag = [&v] {
      std::uint32_t t = 0;
      if (v.size() >= sizeof t) std::memcpy(&t, v.data(), sizeof t);
      return t;
    };
    if (!v.empty() && peek_tag() != kBreakdownTag) {
      const auto count = get<std::uint32_t>(v);
      if (count == 0 || count > 32) throw std::runtime_error("bad aov count " + std::to_string(count));
      for (std::uint32_t i = 0; i < count; ++i) {
        auto m = get<std::uint64_t>(v);
        if (m > v.size()) throw std::runtime_error("truncated aov film");
        s.aov_films.emplace_back(v.begin(), v.begin() + std::ptrdiff_t(m));
        v.remove_prefix(m);
      }
    }
    if (!v.empty()) {
      if (get<std::uint32_t>(v) != kBreakdownTag) throw std::runtime_error("trailing bytes");
      for (std::string* t : {&s.breakdown_samples, &s.breakdown_state}) {
        auto m = get<std::uint64_t>(v);
        if (m > v.size()) throw std::runtime_error("truncated breakdown");
        t->assign(v.data(), m);
        v.remove_prefix(m);
      }
      if (!v.empty()) throw std::runtime_error("trailing bytes");
    }
    return s;
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(path + ": " + e.what());
  }
}

}  // namespace omega::daemon
