#pragma once
// Content-addressed asset store under STATE/assets/ab/abcdef...: the name is the SHA-256 of the
// bytes. Hashes are checked when an asset is written and again when it is read for a job, so a
// corrupted file is never used. Any thread (no shared mutable state besides the filesystem).
#include <cstdint>
#include <set>
#include <string>
#include <string_view>
#include <vector>

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

  // Loop thread. Keeps the cache at most max_bytes by deleting least recently used entries
  // (mtime, refreshed by put and materialize) that no job needs: an entry with a link count of 1
  // is in no job's files/ (jobs hold hard links), and `keep` names the assets of submits in
  // progress. Returns the evicted hashes; if everything left is in use the cache stays over.
  std::vector<std::string> evict(std::uint64_t max_bytes, const std::set<std::string>& keep);

 private:
  std::string dir_;
};

}  // namespace omega::daemon
