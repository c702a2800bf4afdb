#pragma once
// Content-addressed asset store under STATE/assets/ab/abcdef...: the name is the SHA-256 of the
// bytes. Hashes are checked when an asset is written and again when it is read for a job, so a
// corrupted file is never used. Any thread (no shared mutable state besides the filesystem).
#include <string>
#include <string_view>

namespace omega::daemon {

std::string sha256_hex(std::string_view data);

class AssetCache {
 public:
  explicit AssetCache(std::string dir);  // creates dir

  bool has(const std::string& sha) const;
  // Stores data, which must hash to sha (else std::runtime_error "hash mismatch").
  void put(const std::string& sha, std::string_view data);
  // Places the asset at dest (hard link, or a copy across file systems) after re-checking its
  // hash and size. A corrupt entry is deleted and std::runtime_error thrown.
  void materialize(const std::string& sha, std::uint64_t size, const std::string& dest) const;
  std::string path_of(const std::string& sha) const;

 private:
  std::string dir_;
};

}  // namespace omega::daemon
