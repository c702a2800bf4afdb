#include "daemon/render_worker.h"

#include <filesystem>

#include <tbb/parallel_for.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>

#include <fmt/format.h>

#include "film/partial_exr.h"
#include "integrator/render_session.h"
#include "pathspace/classify.h"
#include "pathspace/lpe_classify.h"
#include "scene/scene.h"
#include "scene/scene_error.h"

namespace omega::daemon {

const char* to_string(StopKind k) {
  switch (k) {
    case StopKind::none: return "none";
    case StopKind::pause: return "pause";
    case StopKind::cancel: return "cancel";
    case StopKind::preempt: return "preempt";
    case StopKind::drain: return "drain";
    case StopKind::now: return "now";
  }
  return "?";
}

namespace {

// omega.breakdown and omega.breakdown_samples, when the job has a breakdown: whole images only
// (fetch, result), not every tile.
void add_breakdown_attributes(const FilmSnapshot& s, ExrMeta& m) {
  if (s.breakdown.empty()) return;
  m.attributes["omega.breakdown"] = s.breakdown;
  m.attributes["omega.breakdown_samples"] = s.breakdown_samples;
}

ExrMeta meta_of(const FilmSnapshot& s) {
  ExrMeta m;
  m.spp = static_cast<long long>(s.spp);
  m.time_s = s.elapsed_s;
  m.integrator = s.integrator.empty() ? "path" : s.integrator;
  m.seed = s.seed;
  m.nonfinite = s.nonfinite;
  m.rel_error = s.rel_error.value_or(0);
  return m;
}

}  // namespace

EncodedTile encode_tile(const Film& film, const Rect& r, const ExrMeta& meta, const std::vector<AovFilm>& aovs) {
  ExrMeta m = meta;
  m.compress = false;  // see ExrMeta::compress: ZIP cost a watched job ~5% of its CPU time
  if (!aovs.empty()) append_aov_tile_layers(aovs, r, m);
  const std::vector<std::uint8_t> bytes = encode_exr_tile(film, r, m);
  EncodedTile t;
  t.rect = protocol::Rect{std::uint32_t(r.x0), std::uint32_t(r.y0), std::uint32_t(r.x1), std::uint32_t(r.y1)};
  t.exr = std::make_shared<const std::string>(bytes.begin(), bytes.end());
  return t;
}

std::vector<EncodedTile> encode_tiles(const Film& film, int tile_size, const FilmSnapshot& meta,
                                      const std::vector<AovFilm>& aovs) {
  std::vector<Rect> rects = film.tiles(tile_size);
  std::vector<EncodedTile> out(rects.size());
  ExrMeta m = meta_of(meta);
  tbb::parallel_for(std::size_t(0), rects.size(), [&](std::size_t i) { out[i] = encode_tile(film, rects[i], m, aovs); });
  return out;
}

std::string encode_image(const Film& film, const FilmSnapshot& meta, const std::vector<AovFilm>& aovs) {
  ExrMeta m = meta_of(meta);
  append_aov_layers(aovs, m);
  add_breakdown_attributes(meta, m);
  auto bytes = encode_exr_tile(film, film.crop(), m);
  return std::string(bytes.begin(), bytes.end());
}

std::vector<AovFilm> aov_films_of(const FilmDesc& film, const FilmSnapshot& snap) {
  if (snap.aov_films.size() != film.aovs.size())
    throw std::runtime_error("the film names " + std::to_string(film.aovs.size()) + " aovs, its snapshot holds " +
                             std::to_string(snap.aov_films.size()));
  std::vector<AovFilm> out;
  for (std::size_t i = 0; i < film.aovs.size(); ++i)
    out.push_back({film.aovs[i].name, film.aovs[i].expr, Film::deserialize(film, snap.aov_films[i])});
  return out;
}

RenderWorker::RenderWorker(WorkerSpec spec, Log& log, PassFn on_pass, FinishFn on_finish, TileFn on_tile)
    : spec_(std::move(spec)),
      log_(log),
      on_pass_(std::move(on_pass)),
      on_finish_(std::move(on_finish)),
      on_tile_(std::move(on_tile)) {}

RenderWorker::~RenderWorker() {
  request_stop(StopKind::now);
  join();
}

void RenderWorker::start() { thread_ = std::thread([this] { run(); }); }

void RenderWorker::join() {
  if (thread_.joinable()) thread_.join();
}

void RenderWorker::request_stop(StopKind k) {
  // A stronger request wins: now > cancel > pause/preempt > drain; never downgrade.
  auto rank = [](StopKind s) {
    switch (s) {
      case StopKind::none: return 0;
      case StopKind::drain: return 1;
      case StopKind::preempt: return 2;
      case StopKind::pause: return 3;
      case StopKind::cancel: return 4;
      case StopKind::now: return 5;
    }
    return 0;
  };
  std::lock_guard lock(mutex_);
  StopKind cur = stop_requested();
  if (rank(k) <= rank(cur)) return;
  stop_.store(static_cast<int>(k));
  if (k != StopKind::drain && session_) session_->abort();
}

namespace {

bool disk_full(const std::string& what) {
  return what.find("No space left") != std::string::npos || what.find("quota exceeded") != std::string::npos;
}

}  // namespace

// Driver thread. The film is clean and in memory when the halt is reached, so a full disk at
// that moment (another job's upload refused for space, a log not yet rotated) is waited out
// rather than failing an accepted job: the write is tried again every second, for up to
// kFullDiskPatience, while no stop is requested. Any other error fails at once.
void RenderWorker::write_final(const char* what, const std::function<void()>& write) {
  constexpr auto kFullDiskPatience = std::chrono::minutes(10);
  const auto give_up = std::chrono::steady_clock::now() + kFullDiskPatience;
  for (bool warned = false;;) {
    try {
      write();
      if (warned) log_.info("job {}: {} written once the disk had room", spec_.job, what);
      return;
    } catch (const std::exception& e) {
      if (!disk_full(e.what()) || std::chrono::steady_clock::now() >= give_up || stop_requested() != StopKind::none)
        throw;
      if (!warned) log_.warn("job {}: {} not written ({}); trying again every second", spec_.job, what, e.what());
      warned = true;
    }
    for (int i = 0; i < 20 && stop_requested() == StopKind::none; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

void RenderWorker::run() {
  using Clock = std::chrono::steady_clock;
  WorkerResult result;
  result.job = spec_.job;
  std::shared_ptr<const FilmSnapshot> last;
  bool last_on_disk = false;
  try {
    SceneDesc desc = load_job_scene(spec_.paths, spec_.name, spec_.integrator, spec_.sampler, spec_.allowed_roots);
    // Any stop, drain included, abandons a build: nothing of it is worth keeping, and a slow
    // build must not hold up a cancel or a shutdown.
    std::unique_ptr<Scene> scene = Scene::build(desc, [this] { return stop_requested() != StopKind::none; });
    // Path classes this integrator cannot sample go with the result like any other warning.
    for (const auto& w : scene->warnings()) desc.warnings.push_back(w);
    for (auto& w : path_space_warnings(*scene, desc.integrator.type)) desc.warnings.push_back(std::move(w));
    for (auto& w : aov_warnings(*scene, LpeSet(desc.sensor.film.aovs), desc.integrator.type))
      desc.warnings.push_back(std::move(w));

    std::shared_ptr<const FilmSnapshot> resume = spec_.resume;
    if (!resume) {
      std::optional<FilmSnapshot> ck;
      try {
        ck = read_checkpoint(spec_.paths.checkpoint());
      } catch (const std::exception& e) {
        // A corrupt checkpoint loses only the work since the start: samples depend on (seed,
        // pixel, index) alone, so rendering again from 0 spp gives the same image. Keep the file
        // for inspection.
        std::error_code ec;
        std::filesystem::rename(spec_.paths.checkpoint(), spec_.paths.checkpoint() + ".corrupt", ec);
        log_.error("job {}: corrupt checkpoint ({}); moved to checkpoint.bin.corrupt, rendering again from 0 spp",
                   spec_.job, e.what());
      }
      if (ck) {
        resume = std::make_shared<const FilmSnapshot>(std::move(*ck));
        last_on_disk = true;
      }
    }
    if (resume && resume->aov_films.size() != desc.sensor.film.aovs.size()) {
      // Not this job's film (its scene names other AOVs): resuming the beauty without its AOVs
      // would leave them short of samples. Samples depend on (seed, pixel, index) alone, so
      // starting again gives the same image.
      log_.error("job {}: checkpoint holds {} aovs, the scene names {}; rendering again from 0 spp", spec_.job,
                 resume->aov_films.size(), desc.sensor.film.aovs.size());
      resume = nullptr;
      last_on_disk = false;
    }
    last = resume;

    RenderSettings rs;
    rs.halt = desc.sensor.halt;
    const protocol::Halt& h = spec_.halt;
    if (h.spp || h.time_s || h.target_error) {
      rs.halt = HaltDesc{};
      if (h.spp) rs.halt.spp = static_cast<long long>(*h.spp);
      rs.halt.time_s = h.time_s;
      rs.halt.target_error = h.target_error;
    }
    const double base_elapsed = resume ? resume->elapsed_s : 0;
    const std::uint64_t base_pass = resume ? resume->pass : 0;
    const std::uint64_t base_nonfinite = resume ? resume->nonfinite : 0;
    if (rs.halt.time_s) rs.halt.time_s = std::max(1e-3, *rs.halt.time_s - base_elapsed);
    // Under a share, twice as many threads as tile slots: a job's threads that finish a tile
    // must find another of its threads already waiting, or a freed slot falls to a lighter job
    // (work conservation) and the heavier one cannot reach its share.
    rs.threads = spec_.share ? 2 * resolve_threads(spec_.threads) : spec_.threads;
    rs.seed = spec_.seed;
    rs.tile_size = spec_.tile_size;
    rs.first_sample = resume ? static_cast<long long>(resume->spp) : 0;
    rs.integrator = desc.integrator;
    bool time_done = h.time_s && resume && resume->elapsed_s >= *h.time_s;
    if (time_done) rs.halt.spp = static_cast<long long>(resume->spp);  // nothing left to render

    RenderSession session(*scene, rs);
    if (resume) {
      session.film() = Film::deserialize(desc.sensor.film, resume->film);
      if (AovImages* aovs = session.aovs())
        for (std::size_t i = 0; i < aovs->size(); ++i)
          aovs->films()[i].film = Film::deserialize(desc.sensor.film, resume->aov_films[i]);
    }
    // The breakdown's sums go on from the checkpoint's, when it holds them for this region and
    // length (a job checkpointed before it had them restarts its breakdown at the resume).
    long long breakdown_first = rs.first_sample;
    if (BreakdownCollector* bc = session.breakdown(); bc && resume && !resume->breakdown_state.empty()) {
      try {
        BreakdownState st = parse_breakdown_state(resume->breakdown_state);
        const SampleRange covered = parse_sample_range(resume->breakdown_samples);
        if (st.region == bc->region_name() && st.max_length == bc->max_length() && covered.end == rs.first_sample) {
          bc->add_base(st.stats);
          breakdown_first = covered.begin;
        }
      } catch (const std::invalid_argument& e) {
        log_.warn("job {}: the checkpoint's breakdown is unreadable ({}); it restarts at {} spp", spec_.job, e.what(),
                  rs.first_sample);
      }
    }
    static const std::vector<AovFilm> kNoAovs;
    const std::vector<AovFilm>& aov_films = session.aovs() ? session.aovs()->films() : kNoAovs;
    {
      std::lock_guard lock(mutex_);
      session_ = &session;
      StopKind k = stop_requested();
      if (k != StopKind::none && k != StopKind::drain) session.abort();
    }
    log_.info("job {}: rendering from {} spp ({} threads)", spec_.job, rs.first_sample, resolve_threads(spec_.threads));

    if (spec_.share)
      session.set_tile_runner([share = spec_.share, job = spec_.job](const std::function<void()>& work) {
        share->run(job, work);
      });
    // Tiles stream as they finish (path tracing; RenderSession::set_on_tile) while someone
    // watches. A pass whose every tile went out that way needs no encoding at its boundary.
    const std::size_t tile_count = session.film().tiles(spec_.tile_size).size();
    std::atomic<std::size_t> streamed{0};
    std::atomic<std::uint64_t> pass_in_progress{base_pass + 1};
    std::atomic<double> last_rel_error{resume && resume->rel_error ? *resume->rel_error : 0.0};
    const auto run_start = Clock::now();
    if (on_tile_) {
      session.set_on_tile([&](const Rect& rect, long long spp) {  // render threads
        if (!watched_.load()) return;
        ExrMeta m;
        m.spp = spp;
        m.time_s = base_elapsed + std::chrono::duration<double>(Clock::now() - run_start).count();
        m.integrator = integrator_name(desc.integrator.type);
        m.seed = spec_.seed;
        m.rel_error = last_rel_error.load();
        TileUpdate t;
        t.job = spec_.job;
        t.pass = pass_in_progress.load();
        t.spp = static_cast<std::uint64_t>(spp);
        t.tile = encode_tile(session.film(), rect, m, aov_films);
        t.first = first_tile_.exchange(false);
        streamed.fetch_add(1);
        on_tile_(std::move(t));
      });
    }

    auto last_ckpt = Clock::now();
    PassReport final_report = session.run([&](const PassReport& r) {
      auto snap = std::make_shared<FilmSnapshot>();
      snap->spp = static_cast<std::uint64_t>(r.spp);
      snap->pass = base_pass + static_cast<std::uint64_t>(r.pass);
      snap->elapsed_s = base_elapsed + r.elapsed_s;
      snap->nonfinite = base_nonfinite + r.nonfinite;
      if (std::isfinite(r.error.mean_rel_error)) snap->rel_error = r.error.mean_rel_error;
      snap->film = session.film().serialize();
      for (const AovFilm& a : aov_films) snap->aov_films.push_back(a.film.serialize());
      snap->integrator = integrator_name(desc.integrator.type);
      snap->seed = spec_.seed;
      if (const BreakdownCollector* bc = session.breakdown()) {
        BreakdownState st{bc->region_name(), bc->max_length(), bc->stats()};
        snap->breakdown = breakdown_csv(make_breakdown_report(st.stats, st.region, st.max_length));
        snap->breakdown_state = breakdown_state_text(st);
        snap->breakdown_samples = fmt::format("{}:{}", breakdown_first, r.spp);
      }
      last = snap;
      last_on_disk = false;
      const bool draining = stop_requested() == StopKind::drain;
      const double since = std::chrono::duration<double>(Clock::now() - last_ckpt).count();
      if (draining || since >= spec_.checkpoint_interval_s) {
        // A checkpoint that cannot be written (a full disk) costs only the protection it gives:
        // the render goes on, the next one is tried at the next due boundary, and a crash
        // meanwhile resumes from the previous one. The job is not failed for it.
        try {
          write_checkpoint(spec_.paths.checkpoint(), *snap);
          last_on_disk = true;
        } catch (const std::exception& e) {
          log_.warn("job {}: checkpoint at {} spp not written ({}); rendering on", spec_.job, snap->spp, e.what());
        }
        last_ckpt = Clock::now();
      }
      PassUpdate u;
      u.job = spec_.job;
      u.snapshot = snap;
      u.film = desc.sensor.film;
      u.progress.pass = snap->pass;
      u.progress.spp = snap->spp;
      u.progress.elapsed_s = snap->elapsed_s;
      u.progress.rel_error = snap->rel_error;
      u.progress.samples_per_s = r.samples_per_s;
      u.tiles_streamed = streamed.exchange(0) == tile_count && !r.cut;
      if (watched_.load() && !u.tiles_streamed) u.tiles = encode_tiles(session.film(), spec_.tile_size, *snap, aov_films);
      pass_in_progress.store(snap->pass + 1);
      if (snap->rel_error) last_rel_error.store(*snap->rel_error);
      on_pass_(std::move(u));
      if (draining) session.abort();  // stop at this boundary: the film is clean and on disk
    });
    (void)final_report;
    {
      std::lock_guard lock(mutex_);
      session_ = nullptr;
    }
    result.last = last;
    if (!session.aborted()) {
      // Halt reached: the film is clean. Keep a final checkpoint and the result image.
      if (last && !last_on_disk) write_final("final checkpoint", [&] { write_checkpoint(spec_.paths.checkpoint(), *last); });
      FilmSnapshot meta = last ? *last : FilmSnapshot{};
      ExrMeta m;
      m.spp = static_cast<long long>(meta.spp);
      m.time_s = meta.elapsed_s;
      m.integrator = integrator_name(desc.integrator.type);
      m.seed = spec_.seed;
      m.attributes["omega.sampler"] = sampler_name(desc.integrator.sampler);
      m.nonfinite = meta.nonfinite;
      m.warnings = desc.warnings;
      m.rel_error = meta.rel_error.value_or(0);
      append_aov_layers(aov_films, m);
      add_breakdown_attributes(meta, m);
      write_final("result image", [&] { write_exr(spec_.paths.result(), session.film(), m); });
      result.outcome = WorkerResult::Outcome::done;
    } else {
      result.outcome = WorkerResult::Outcome::stopped;
      result.stop = stop_requested();
      // The film holds part of an unfinished pass: what survives is the last boundary.
      if (last && !last_on_disk && result.stop != StopKind::cancel) write_checkpoint(spec_.paths.checkpoint(), *last);
    }
  } catch (const SceneError& e) {
    result.outcome = WorkerResult::Outcome::failed;
    result.message = e.what();
  } catch (const std::exception& e) {
    result.outcome = WorkerResult::Outcome::failed;
    result.message = e.what();
  }
  {
    std::lock_guard lock(mutex_);
    session_ = nullptr;
  }
  if (result.outcome == WorkerResult::Outcome::failed) {
    StopKind k = stop_requested();
    if (k != StopKind::none) {  // a failure while stopping is just a stop (e.g. the checkpoint dir went away)
      result.outcome = WorkerResult::Outcome::stopped;
      result.stop = k;
    }
  }
  result.last = last;
  on_finish_(std::move(result));
}

}  // namespace omega::daemon
