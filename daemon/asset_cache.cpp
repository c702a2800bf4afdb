#include "daemon/asset_cache.h"

#include <openssl/evp.h>
#include <unistd.h>

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
  if (::link(src.c_str(), dest.c_str()) == 0) return;
  write_file_atomic(dest, data);
}

}  // namespace omega::daemon
