#pragma once
// One running job: a driver thread that builds the scene and runs a RenderSession, whose passes
// run on a oneTBB arena. At each pass boundary it snapshots the film, checkpoints it when due,
// encodes the tiles when someone watches, and reports to the loop through callbacks.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "daemon/checkpoint.h"
#include "daemon/job_scene.h"
#include "daemon/log.h"
#include "daemon/thread_share.h"
#include "film/aov_film.h"
#include "film/film.h"
#include "protocol/messages.h"

namespace omega {
class RenderSession;
}

namespace omega::daemon {

enum class StopKind : int { none = 0, pause, cancel, preempt, drain, now };
const char* to_string(StopKind k);

struct EncodedTile {
  protocol::Rect rect;
  std::shared_ptr<const std::string> exr;
};

// What a pass boundary produced. Immutable; travels from the driver thread to the loop.
struct PassUpdate {
  std::uint64_t job = 0;
  std::shared_ptr<const FilmSnapshot> snapshot;
  FilmDesc film;
  protocol::ProgressInfo progress;
  std::vector<EncodedTile> tiles;  // empty unless someone watches and the pass did not stream them
  bool tiles_streamed = false;     // every tile of the pass went out as a TileUpdate already
};

// One tile streamed in the middle of a pass (path tracing): its pixels hold `spp` samples.
struct TileUpdate {
  std::uint64_t job = 0;
  std::uint64_t pass = 0;  // the pass in progress
  std::uint64_t spp = 0;
  EncodedTile tile;
  bool first = false;  // the first tile streamed since someone began watching: it goes at once
};

struct WorkerResult {
  std::uint64_t job = 0;
  enum class Outcome { done, stopped, failed } outcome = Outcome::failed;
  StopKind stop = StopKind::none;  // why it stopped (outcome stopped)
  std::string message;             // why it failed
  std::shared_ptr<const FilmSnapshot> last;  // the newest pass-boundary film, if any
};

struct WorkerSpec {
  std::uint64_t job = 0;
  JobPaths paths;
  std::string name;
  std::string integrator;
  std::string sampler;  // empty: the scene's
  protocol::Halt halt;
  std::uint64_t seed = 0;
  int threads = 0;
  int tile_size = 32;
  double checkpoint_interval_s = 30;
  std::vector<std::string> allowed_roots;
  std::shared_ptr<const FilmSnapshot> resume;  // null: read the checkpoint file, if any
  ThreadShare* share = nullptr;  // the daemon's, not owned: outlives the worker; null: no sharing
};

class RenderWorker {
 public:
  // Both callbacks run on the driver thread; they must only hand work to the loop (post).
  using PassFn = std::function<void(PassUpdate)>;
  using FinishFn = std::function<void(WorkerResult)>;
  // Runs on the render threads (several at once) while someone watches; must only post.
  using TileFn = std::function<void(TileUpdate)>;

  RenderWorker(WorkerSpec spec, Log& log, PassFn on_pass, FinishFn on_finish, TileFn on_tile = {});
  ~RenderWorker();  // joins
  RenderWorker(const RenderWorker&) = delete;
  RenderWorker& operator=(const RenderWorker&) = delete;

  // Loop thread. Starts the driver thread.
  void start();
  // Loop thread; takes mutex_. pause/cancel/preempt/now abort the pass at the next tile
  // boundary; drain lets the pass finish and stops at its boundary. A stronger kind overrides.
  void request_stop(StopKind k);
  StopKind stop_requested() const { return static_cast<StopKind>(stop_.load()); }
  // Any thread: whether pass boundaries should encode tiles (someone subscribes).
  void set_watched(bool w) {
    if (w && !watched_.exchange(true)) first_tile_.store(true);
    if (!w) watched_.store(false);
  }
  void join();
  std::uint64_t job() const { return spec_.job; }

 private:
  void run();  // driver thread
  // Driver thread: write(), tried again while the disk is full (see the definition).
  void write_final(const char* what, const std::function<void()>& write);

  WorkerSpec spec_;
  Log& log_;
  PassFn on_pass_;
  FinishFn on_finish_;
  TileFn on_tile_;
  std::thread thread_;
  std::atomic<int> stop_{0};
  std::atomic<bool> watched_{false};
  std::atomic<bool> first_tile_{true};  // the next streamed tile is TileUpdate::first
  std::mutex mutex_;                        // guards session_
  omega::RenderSession* session_ = nullptr;  // set by the driver while run() is in progress
};

// Any thread: encodes one tile of a film (whose pixels no thread is writing), with the tile of
// each AOV as layers aov.NAME and aov.NAME.var.
EncodedTile encode_tile(const Film& film, const Rect& rect, const ExrMeta& meta, const std::vector<AovFilm>& aovs = {});
// Any thread: encodes every tile of a film (in parallel) for subscribers.
std::vector<EncodedTile> encode_tiles(const Film& film, int tile_size, const FilmSnapshot& meta,
                                      const std::vector<AovFilm>& aovs = {});
// Any thread: the whole film as one in-memory EXR.
std::string encode_image(const Film& film, const FilmSnapshot& meta, const std::vector<AovFilm>& aovs = {});
// Any thread: the AOV films a snapshot holds, named by the job's film. Throws
// std::runtime_error when the snapshot holds another number of AOVs than the film names.
std::vector<AovFilm> aov_films_of(const FilmDesc& film, const FilmSnapshot& snap);

}  // namespace omega::daemon
