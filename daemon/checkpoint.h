#pragma once
// Checkpoints: the film's statistics plus the sample count they hold, written atomically (temp
// file, fsync, rename, fsync of the directory) so that after a crash a job resumes from a film
// that holds exactly samples [0, spp) of every pixel.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace omega::daemon {

// A film at a pass boundary. Immutable once made; shared between threads by shared_ptr.
struct FilmSnapshot {
  std::uint64_t spp = 0;   // samples per pixel in the film (the next pass starts here)
  std::uint64_t pass = 0;  // completed passes over the job's whole life
  double elapsed_s = 0;    // render time over the job's whole life
  std::uint64_t nonfinite = 0;
  std::optional<double> rel_error;
  std::vector<std::uint8_t> film;  // Film::serialize()
  // Film::serialize() of each light path expression output, in the film's `aov` order (empty
  // without AOVs; a checkpoint then has no AOV section, byte for byte as before AOVs existed).
  std::vector<std::vector<std::uint8_t>> aov_films;
  // The path-class breakdown (film key `breakdown`): its exact sums (breakdown_state_text) and
  // the samples they cover ("A:B"), in an optional section after the AOVs, so that a resumed job
  // goes on adding to them. Empty without a breakdown.
  std::string breakdown_state, breakdown_samples;
  // In memory only (not in the checkpoint file): what tile EXRs report in their omega.* header,
  // and the breakdown's report (breakdown_csv text) for fetched images.
  std::string integrator;  // "path", "light" or "bdpt"; empty until known
  std::uint64_t seed = 0;
  std::string breakdown;
};

// Any thread. Writes PATH.tmp, fsyncs it, renames it over PATH and fsyncs the directory.
// Throws std::runtime_error naming the path.
void write_file_atomic(const std::string& path, std::string_view data);
std::string read_file(const std::string& path);  // throws std::runtime_error naming the path

// Any thread. Throws std::runtime_error naming the path for I/O errors, a bad magic, a
// truncated file or a checksum mismatch.
void write_checkpoint(const std::string& path, const FilmSnapshot& s);
std::optional<FilmSnapshot> read_checkpoint(const std::string& path);  // nullopt if absent

}  // namespace omega::daemon
