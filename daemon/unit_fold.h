#pragma once
// The merged image of a worker job: finished work units (parts, as `omega render --samples A:B`
// writes them) folded in order of their first sample, exactly as `omega merge` folds the same
// parts (merge_parts: an empty film, then Film::merge of each part left to right). So the
// daemon's result is bit-identical to `omega merge` of the units, and within the rounding bound
// of docs/farm.md ("How exact") of `omega render --spp N`.
//
// A UnitFold is touched only on the daemon's background thread, whose tasks run one at a time in
// submission order: the loop thread hands it units in sample order and never reads it.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "daemon/checkpoint.h"
#include "daemon/job_scene.h"
#include "daemon/render_worker.h"
#include "film/film.h"
#include "film/partial_exr.h"
#include "integrator/breakdown.h"

namespace omega::daemon {

struct UnitFold {
  std::optional<Film> film;  // null until the first unit (or load) sets it
  FilmDesc desc;
  std::string integrator;  // the job's effective integrator and sampler names
  std::string sampler;
  std::uint64_t seed = 0;
  std::uint64_t spp = 0;    // samples [0, spp) are merged
  std::uint64_t units = 0;  // units merged
  double time_s = 0;        // render time summed over the units
  std::uint64_t nonfinite = 0;
  std::vector<std::string> warnings;
  std::string scene_hash;
  // The job's light path expression outputs (desc.aovs, in that order), folded as the film is,
  // and its breakdown's exact sums (film key `breakdown`); a unit lacking the sums (a worker
  // older than the breakdown) leaves the job without one, with a warning.
  std::vector<AovFilm> aovs;
  std::optional<BreakdownState> breakdown;
  bool breakdown_dropped = false;
};

// What one fold step gives the loop: the new image (and its tiles when someone watches).
struct FoldUpdate {
  std::uint64_t job = 0;
  std::shared_ptr<const FilmSnapshot> snapshot;
  FilmDesc film;
  std::vector<EncodedTile> tiles;
  std::string error;  // a unit that could not be read: the job fails
};

// Background thread. Reads the job's scene (for the film) the first time.
void init_fold(UnitFold& f, const JobPaths& jp, const std::string& name, const std::string& integrator,
               const std::string& sampler, std::uint64_t seed, const std::vector<std::string>& allowed_roots);

// Background thread: checks that the part at `path` holds exactly [begin, end) of this job (seed,
// integrator, sampler, film) and returns it. Throws std::runtime_error saying what is wrong.
PartialRender check_part(const UnitFold& f, const std::string& path, std::uint64_t begin, std::uint64_t end);

// Background thread: merges the parts at `paths` (whose ranges continue f.spp, in order) and
// returns the snapshot; tiles only when `tiles` (someone watches).
FoldUpdate fold_parts(UnitFold& f, std::uint64_t job, const std::vector<std::string>& paths, bool tiles,
                      int tile_size);

// Background thread: writes the merged film as the job's result, a part holding [0, f.spp), so
// it merges on with other parts (`omega merge`). Throws std::runtime_error naming the path.
void write_fold_result(const UnitFold& f, const std::string& path);

// STATE/jobs/ID/units/NUMBER.exr
std::string unit_part_path(const JobPaths& jp, std::uint64_t unit);

// The assets a job was submitted with, recorded beside its scene at accept time so that workers
// can be told their hashes (jobs/ID/assets.txt: "SHA256 SIZE NAME" lines). Any thread.
std::string format_asset_list(const std::vector<protocol::AssetRef>& assets);
std::vector<protocol::AssetRef> parse_asset_list(const std::string& text);

}  // namespace omega::daemon
