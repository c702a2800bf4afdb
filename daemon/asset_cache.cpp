#include "daemon/asset_cache.h"

#include <openssl/evp.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <tuple>

#include <filesystem>
#include <memory>
#include <stdexcept>

#include "daemon/checkpoint.h"

namespace omega::daemon {

namespace fs = std::filesystem;

std::string sha256_hex(std::string_view data) {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), &EVP_MD_CTX_free);
  unsigned char md[EVP_MAX_MD_SIZE];
  unsigned int len = 0;
  if (!ctx || EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) != 1 ||
      EVP_DigestUpdate(ctx.get(), data.data(), data.size()) != 1 || EVP_DigestFinal_ex(ctx.get(), md, &len) != 1)
    throw std::runtime_error("SHA-256 failed (OpenSSL)");
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  for (unsigned i = 0; i < len; ++i) {
    out += kHex[md[i] >> 4];
    out += kHex[md[i] & 15];
  }
  return out;
}

AssetCache::AssetCache(std::string dir) : dir_(std::move(dir)) { fs::create_directories(dir_); }

std::string AssetCache::path_of(const std::string& sha) const { return dir_ + "/" + sha.substr(0, 2) + "/" + sha; }

bool AssetCache::has(const std::string& sha) const {
  std::error_code ec;
  return fs::is_regular_file(path_of(sha), ec);
}

void AssetCache::put(const std::string& sha, std::string_view data) {
  if (sha256_hex(data) != sha) throw std::runtime_error("asset " + sha + ": hash mismatch");
  fs::create_directories(dir_ + "/" + sha.substr(0, 2));
  write_file_atomic(path_of(sha), data);
}

void AssetCache::materialize(const std::string& sha, std::uint64_t size, const std::string& dest) const {
  std::string src = path_of(sha);
  std::string data = read_file(src);
  if (data.size() != size || sha256_hex(data) != sha) {
    std::error_code ec;
    fs::remove(src, ec);
    throw std::runtime_error("cached asset " + sha + " is corrupt (removed); send it again");
  }
  fs::create_directories(fs::path(dest).parent_path());
  std::error_code ec;
  fs::last_write_time(src, fs::file_time_type::clock::now(), ec);  // most recently used
  if (::link(src.c_str(), dest.c_str()) == 0) return;
  write_file_atomic(dest, data);
}

std::vector<std::string> AssetCache::evict(std::uint64_t max_bytes, const std::set<std::string>& keep) {
  std::uint64_t total = 0;
  std::vector<std::tuple<std::int64_t, std::string, std::uint64_t>> free;  // (mtime ns, sha, size)
  std::error_code ec;
  for (const auto& e : fs::recursive_directory_iterator(dir_, ec)) {
    struct stat st{};
    if (::lstat(e.path().c_str(), &st) != 0 || !S_ISREG(st.st_mode)) continue;
    total += std::uint64_t(st.st_size);
    std::string sha = e.path().filename().string();
    if (st.st_nlink == 1 && !keep.count(sha))
      free.emplace_back(std::int64_t(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec, sha, std::uint64_t(st.st_size));
  }
  std::vector<std::string> evicted;
  if (total <= max_bytes) return evicted;
  std::sort(free.begin(), free.end());
  for (const auto& [t, sha, size] : free) {
    if (total <= max_bytes) break;
    if (fs::remove(path_of(sha), ec)) {
      total -= size;
      evicted.push_back(sha);
    }
  }
  return evicted;
}

}  // namespace omega::daemon
