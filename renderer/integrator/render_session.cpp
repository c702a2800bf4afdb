#include "integrator/render_session.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <span>

#include "film/filter.h"
#include "integrator/ordered_dispatch.h"
#include <chrono>
#include <cmath>
#include <stdexcept>
#include <thread>

namespace omega {

namespace {

using Clock = std::chrono::steady_clock;

constexpr long long kDefaultSpp = 64;
constexpr long long kMaxPassSpp = 256;
constexpr double kPassSeconds = 1.0;
constexpr long long kMinSppForErrorHalt = 16;
constexpr size_t kWavePixels = size_t(1) << 18;  // variance estimates below this are too noisy to stop on

PathTracerSettings tracer_settings(const IntegratorDesc& d) {
    return {d.max_depth, d.rr_depth, d.light_sampling, d.mirror_connector};
}

// Seconds of work since t0, for ordering tiles (always the real clock: RenderSettings::clock is
// what time limits read, and tests that inject it count its calls).
double seconds_since(std::chrono::steady_clock::time_point t0) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int resolve_threads(int threads) {
    if (threads > 0) return threads;
    return std::max(1, int(std::thread::hardware_concurrency()));
}

void RenderSession::check_settings(const RenderSettings& settings) {
    if (!settings.integrator.light_sampling && settings.integrator.type != IntegratorType::Path)
        throw std::invalid_argument("light_sampling = false is only available with the path integrator");
}

RenderSession::RenderSession(const Scene& scene, const RenderSettings& settings)
    : scene_(scene), settings_(settings), tracer_(scene, tracer_settings(settings.integrator)), film_(scene.desc().sensor.film) {
    check_settings(settings);
    const FilmDesc& fd = scene.desc().sensor.film;
    if (!fd.aovs.empty()) aovs_ = std::make_unique<AovImages>(fd, fd.aovs);
    const bool splatting = settings.integrator.type != IntegratorType::Path;
    // The settings' breakdown (omega render --breakdown), else the film's (the scene key, which
    // is how a daemon job asks for one).
    if (!settings_.breakdown && fd.breakdown) {
        BreakdownDesc bd;
        bd.max_length = fd.breakdown->length;
        if (const auto& b = fd.breakdown->box) bd.box = Rect{(*b)[0], (*b)[1], (*b)[2], (*b)[3]};
        settings_.breakdown = bd;
    }
    if (settings_.breakdown) breakdown_ = std::make_unique<BreakdownCollector>(*settings_.breakdown, film_.crop(), splatting);
    if (splatting) {
        bdpt_ = std::make_unique<BdptTracer>(scene, settings.integrator);
        if (aovs_) bdpt_->set_aovs(&aovs_->lpes());
        if (breakdown_) bdpt_->set_breakdown(breakdown_->max_length());
        bands_ = std::make_unique<SplatBands>(film_.crop(), film_.filter().radius());
        if (settings.strategy_images_max_k > 0)
            strategies_ = std::make_unique<StrategyImages>(film_.crop(), settings.strategy_images_max_k,
                                                           bdpt_->plan().t0 && bdpt_->strategies().allows(2, 0));
    }
}

void RenderSession::set_schedule_probe(ScheduleProbe* p) {
    if (p && resolve_threads(settings_.threads) != 1)
        throw std::logic_error("RenderSession::set_schedule_probe: the session must run on one thread");
    probe_ = p;
    if (bands_) bands_->set_probe(p);
}

bool RenderSession::tile_may_start() {
    if (aborted() || pass_cut_.load(std::memory_order_relaxed)) return false;
    if (cut_at_ && now() >= *cut_at_) {
        pass_cut_.store(true, std::memory_order_relaxed);
        return false;
    }
    return true;
}

long long RenderSession::render_pass_splatting(tbb::task_arena& arena, const std::vector<Rect>& tiles, long long s0,
                                               long long s1) {
    // Every sample index is one batch: sample i of every pixel's camera subpath plus the splats
    // of every pixel's light subpath i. The batches are i.i.d. estimates of the image, so their
    // spread is the variance, and they reach the film in index order whatever the passes were:
    // a render resumed at any pass boundary, or cut into passes by time, adds exactly the same
    // batches in the same order as one that ran in one go (bit-identical mean and variance).
    long long i = s0;
    for (; i < s1 && !aborted(); ++i) {
        render_sample_index(arena, tiles, i);
        if (pass_cut_.load(std::memory_order_relaxed)) break;  // batch i is in the film only in part
    }
    return i;
}

void RenderSession::render_sample_index(tbb::task_arena& arena, const std::vector<Rect>& tiles, long long i) {
    const Rect crop = film_.crop();
    const Sensor& sensor = scene_.sensor();
    const bool lens = sensor.uses_lens_sample();  // asked once, not per sample
    // The light tracer makes no camera ray: its film and lens numbers are skipped, which draws
    // the same numbers from the independent stream as before (the sobol sampler only moves on).
    const bool camera_ray = bdpt_->uses_camera_ray();
    const uint64_t width = uint64_t(sensor.width);
    const double inv_light_paths_per_sample = 1.0 / double(std::max<long long>(1, crop.area()));
    ZeroedArray<Vec3d>& sums = batch_sums_;
    ZeroedArray<Vec3d>& splats = batch_splats_;
    auto index = [&](int x, int y) { return size_t(y - crop.y0) * size_t(crop.width()) + size_t(x - crop.x0); };
    if (sums.size() != size_t(crop.area())) {
        sums = ZeroedArray<Vec3d>(size_t(crop.area()));
        splats = ZeroedArray<Vec3d>(size_t(crop.area()));
    }
    // Driver thread, nothing in flight: the bands this batch's splats go to.
    bands_->relayout(probe_ ? ScheduleProbe::kLayoutWorkers : arena.max_concurrency());
    bands_->for_each_band(arena, [&](const Rect& rows) {
        const size_t a = index(rows.x0, rows.y0), b = a + size_t(rows.area());
        std::fill(sums.begin() + a, sums.begin() + b, Vec3d(0.0));
        std::fill(splats.begin() + a, splats.begin() + b, Vec3d(0.0));
    });
    AovImages* aovs = aovs_.get();
    if (aovs) aovs->begin_batch();
    const Filter& filter = film_.filter();
    // Which tiles ran: a batch cut at the time limit keeps only their pixels (below).
    std::vector<unsigned char> ran(tiles.size(), 0);

    // Tiles run in waves; each wave's splats are merged in tile order, so the sums are the same
    // for any thread count while memory stays bounded by the wave. A wave holds about
    // kWavePixels light paths (~20 MB of splats): the merge then meets each cache line of a band
    // several times per wave, where 16 tiles per wave missed the cache on nearly every splat of
    // a large film (70% of the merge's time went to that one load).
    // The tiles are the tasks even where they are few per worker (64 at 256x256): cut into strips
    // of rows, 16 tasks a worker, the schedule model @16 (Cornell box) gained 1.5% for bdpt and
    // nothing beyond its noise for light, while a one-thread render with that cut cost 0.989
    // (light) and 0.992 (bdpt) of one with whole tiles (bench/ab_cores.sh).
    const size_t tile_area = tiles.empty() ? 1 : size_t(std::max<long long>(1, tiles.front().area()));
    const size_t wave = std::max(size_t(4 * arena.max_concurrency()), kWavePixels / tile_area);
    tile_costs_.resize(tiles.size());
    const std::vector<uint32_t>& tile_order = tile_costs_.order();
    for (size_t w0 = 0; w0 < tiles.size() && !aborted(); w0 += wave) {
        const size_t w1 = std::min(tiles.size(), w0 + wave);
        // Capacity kept from batch to batch: the tiles' splat lists are rebuilt every batch.
        std::vector<BandedSplats>& tile_splats = banded_tiles_;
        tile_splats.resize(w1 - w0);
        for (auto& t : tile_splats) t.clear();
        std::vector<std::vector<StrategyContribution>> tile_strategy_splats(strategies_ ? w1 - w0 : 0);
        if (probe_) probe_->region_begin("tiles");
        // This wave's tiles, longest first by their cost in the last batch.
        wave_order_.clear();
        for (uint32_t ti : tile_order)
            if (ti >= w0 && ti < w1) wave_order_.push_back(ti);
        for_each_ordered(arena, wave_order_, [&](uint32_t ti) {
            TracerStats& st = stats_.local();
            BdptScratch& scratch = scratch_.local();
            std::vector<Splat>& out = tile_raw_splats_.local();
            std::vector<StrategyContribution>* per = strategies_ ? &sample_strategies_.local() : nullptr;
            bool ran_tile = false;
            ScheduleProbe::TaskTimer timer(probe_, ti);
            run_tile([&] {
                if (!tile_may_start()) return;
                const auto t0 = std::chrono::steady_clock::now();
                ran_tile = true;
                ran[ti] = 1;
                const Rect& tile = tiles[ti];
                out.clear();
                for (int y = tile.y0; y < tile.y1; ++y)
                    for (int x = tile.x0; x < tile.x1; ++x) {
                        uint64_t pixel = uint64_t(y) * width + uint64_t(x);
                        Sampler sampler =
                            Sampler::make(settings_.integrator.sampler, settings_.seed, pixel, uint64_t(i));
                        sampler.start_dimension(dims::kFilm);
                        Vec2 u_film = sampler.next_2d_if(camera_ray);
                        sampler.start_dimension(dims::kLens);
                        Vec2 u_lens = sampler.next_2d_if(lens && camera_ray);
                        Ray ray = camera_ray ? sensor.generate_ray(film_.sample_position(x, y, u_film), u_lens) : Ray{};
                        // The sample appends its splats to the tile's list directly;
                        // a sample that is dropped takes them back out.
                        const size_t first_splat = out.size();
                        if (per) per->clear();
                        Rgb L = bdpt_->sample(ray, sampler, st, scratch, out, per);
                        ++st.samples;
                        const std::span<const Splat> mine(out.data() + first_splat, out.size() - first_splat);
                        bool finite = is_finite(L);
                        for (const Splat& sp : mine) finite = finite && is_finite(sp.value);
                        if (!finite) {
                            ++st.nonfinite;  // the whole sample is dropped, splats included
                            out.resize(first_splat);
                            continue;
                        }
                        sums[index(x, y)] += Vec3d(L);
                        if (aovs)
                            for (size_t a = 0; a < aovs->size(); ++a)
                                aovs->add_camera(a, index(x, y), scratch.aov_camera[a]);
                        if (breakdown_) breakdown_->add_splatting_sample(x, y, scratch, mine, filter);
                        if (per)
                            for (const auto& c : *per) {
                                if (c.splat) tile_strategy_splats[ti - w0].push_back(c);
                                else strategies_->add_camera(x, y, c);
                            }
                    }
                bands_->bucket(out, tile_splats[ti - w0]);
                tile_costs_.record(ti, seconds_since(t0));
            });
            return ran_tile;
        });
        if (probe_) probe_->region_end();
        if (aborted()) return;
        for (const auto& list : tile_strategy_splats)
            for (const auto& c : list) strategies_->add_splat(c, filter, inv_light_paths_per_sample);
        bands_->merge(arena, filter, tile_splats, [&](const Splat& sp, int x, int y, double f) {
            const Vec3d v = Vec3d(sp.value) * (f * inv_light_paths_per_sample);
            splats[index(x, y)] += v;
            if (sp.aov_mask) aovs->add_splat(sp.aov_mask, index(x, y), v);
        });
    }
    if (aborted()) return;
    if (!pass_cut_.load(std::memory_order_relaxed)) {
        // Pixels are independent here: the bands add them in parallel.
        bands_->for_each_band(arena, [&](const Rect& rows) {
            for (int y = rows.y0; y < rows.y1; ++y)
                for (int x = rows.x0; x < rows.x1; ++x) {
                    film_.add_weighted(x, y, sums[index(x, y)] + splats[index(x, y)], 1.0);
                    if (aovs) aovs->add_batch(index(x, y), nullptr);
                }
        });
        if (aovs) aovs->end_batch_complete();
        return;
    }
    // Cut at the time limit: the light paths that ran are a uniform subset of the batch's (their
    // randomness does not depend on where their id lies), so their splats, rescaled to that
    // count, still estimate the light-path part without bias. The batch is added only where the
    // camera part ran too; other pixels simply hold one batch fewer.
    long long traced = 0;
    for (size_t t = 0; t < tiles.size(); ++t)
        if (ran[t]) traced += tiles[t].area();
    if (traced == 0) return;
    const double rescale = double(crop.area()) / double(traced);
    for (size_t t = 0; t < tiles.size(); ++t) {
        if (!ran[t]) continue;
        const Rect& r = tiles[t];
        for (int y = r.y0; y < r.y1; ++y)
            for (int x = r.x0; x < r.x1; ++x) {
                film_.add_weighted(x, y, sums[index(x, y)] + splats[index(x, y)] * rescale, 1.0);
                if (aovs) aovs->add_batch(index(x, y), &rescale);
            }
    }
}

ErrorEstimate RenderSession::estimate_error(tbb::task_arena& arena) {
    error_parts_.resize(film_.error_parts());
    for_each_index(arena, error_parts_.size(), probe_, "error", [&](size_t c) { error_parts_[c] = film_.error_part(c); });
    return film_.error_of(error_parts_);
}

void RenderSession::render_tile(const Rect& tile, long long s0, long long s1, TracerStats& stats) {
    const Sensor& sensor = scene_.sensor();
    const bool lens = sensor.uses_lens_sample();  // asked once, not per sample
    const bool sobol = settings_.integrator.sampler == SamplerType::Sobol;
    std::optional<CameraLpeTracker> lpe;
    if (aovs_) lpe.emplace(aovs_->lpes());
    std::optional<PathClassTracker> classes;
    if (breakdown_) classes.emplace(breakdown_->max_length());
    const uint64_t width = uint64_t(sensor.width);
    for (int y = tile.y0; y < tile.y1; ++y) {
        for (int x = tile.x0; x < tile.x1; ++x) {
            uint64_t pixel = uint64_t(y) * width + uint64_t(x);
            uint64_t key = 0;
            for (long long i = s0; i < s1; ++i) {
                // The sobol key changes only where the index crosses a multiple of 2^32.
                if (sobol && (i == s0 || (uint64_t(i) & 0xffffffffu) == 0))
                    key = Sampler::sobol_key(settings_.seed, pixel, uint64_t(i));
                Sampler sampler = Sampler::make(settings_.integrator.sampler, settings_.seed, pixel, uint64_t(i), key);
                sampler.start_dimension(dims::kFilm);
                Vec2 u_film = sampler.next_2d();
                sampler.start_dimension(dims::kLens);
                Vec2 u_lens = sampler.next_2d_if(lens);
                Vec2 pos = film_.sample_position(x, y, u_film);
                Ray ray = sensor.generate_ray(pos, u_lens);
                if (lpe) lpe->reset();
                if (classes) classes->reset();
                Rgb L = tracer_.radiance(ray, sampler, stats, lpe ? &*lpe : nullptr, classes ? &*classes : nullptr);
                ++stats.samples;
                if (!is_finite(L)) {
                    ++stats.nonfinite;  // discarded: one bad sample must not poison a pixel
                    continue;
                }
                film_.add_sample(x, y, L);
                if (lpe) aovs_->add_samples(x, y, *lpe);
                if (classes) breakdown_->add_path_sample(x, y, *classes);
            }
        }
    }
}

PassReport RenderSession::run(const std::function<void(const PassReport&)>& on_pass) {
    const HaltDesc& halt = settings_.halt;
    const bool no_halt = !halt.spp && !halt.time_s && !halt.target_error;
    const long long spp_limit = halt.spp ? *halt.spp : (no_halt ? kDefaultSpp : -1);
    const std::vector<Rect> tiles = film_.tiles(settings_.tile_size);
    const long long pixels = film_.crop().area();

    tbb::task_arena arena(resolve_threads(settings_.threads));
    auto& stats = stats_;
    const auto t_start = now();
    auto elapsed = [&] { return std::chrono::duration<double>(now() - t_start).count(); };
    // The time limit counts from the origin the caller gave (omega render: its own start).
    const auto origin = settings_.time_origin.value_or(t_start);
    auto budget_used = [&] { return std::chrono::duration<double>(now() - origin).count(); };
    // Strategy images and the breakdown are diagnostics of whole batches: their passes are never cut.
    const bool may_cut = halt.time_s && !strategies_ && !breakdown_;

    PassReport report;
    report.spp = settings_.first_sample;
    long long pass_spp = 1;
    while (!aborted()) {
        long long s0 = report.spp;
        long long n = pass_spp;
        if (spp_limit >= 0) n = std::min(n, spp_limit - s0);
        if (halt.time_s && report.pass > 0 && report.samples_per_s > 0) {
            // Size the pass to the time left; the tile that crosses the limit is the last to start.
            double left = *halt.time_s - budget_used();
            long long fit = (long long)std::ceil(left * report.samples_per_s / double(std::max<long long>(1, pixels)));
            n = std::clamp(fit, 1LL, n);
        }
        if (n <= 0) break;
        const long long s1 = s0 + n;
        // A pass may be cut at the limit only once every pixel has a sample: an image with
        // unrendered pixels is no estimate at all.
        pass_cut_.store(false, std::memory_order_relaxed);
        cut_at_.reset();
        if (may_cut && (report.pass > 0 || settings_.first_sample > 0))
            cut_at_ = origin + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(*halt.time_s));
        long long complete = s0;  // samples every pixel holds after the pass, if it is cut
        if (bdpt_) {
            complete = render_pass_splatting(arena, tiles, s0, s1);
        } else {
            if (probe_) probe_->region_begin("tiles");
            tile_costs_.resize(tiles.size());
            for_each_ordered(arena, tile_costs_.order(), [&](uint32_t t) {
                TracerStats& st = stats.local();
                ScheduleProbe::TaskTimer timer(probe_, t);
                bool ran = false;
                run_tile([&] {
                    if (!tile_may_start()) return;
                    const auto t0 = std::chrono::steady_clock::now();
                    render_tile(tiles[t], s0, s1, st);
                    tile_costs_.record(t, seconds_since(t0) / double(s1 - s0));
                    ran = true;
                    if (on_tile_ && !aborted()) on_tile_(tiles[t], s1);
                });
                return ran;
            });
            if (probe_) probe_->region_end();
        }
        if (aborted()) break;  // a partial pass is not reported as complete

        report.pass += 1;
        report.cut = pass_cut_.load(std::memory_order_relaxed);
        report.spp = report.cut ? complete : s1;
        report.elapsed_s = elapsed();
        TracerStats total;
        for (const auto& s : stats) {
            total.rays += s.rays;
            total.samples += s.samples;
            total.nonfinite += s.nonfinite;
        }
        report.rays = total.rays;
        report.samples = total.samples;
        report.nonfinite = total.nonfinite;
        report.mis_errors = 0;
        for (const auto& sc : scratch_) report.mis_errors += sc.connect.bad_weights;
        report.samples_per_s = report.elapsed_s > 0 ? double(total.samples) / report.elapsed_s : 0;
        report.rays_per_s = report.elapsed_s > 0 ? double(total.rays) / report.elapsed_s : 0;
        report.error = estimate_error(arena);
        if (on_pass) on_pass(report);

        if (spp_limit >= 0 && report.spp >= spp_limit) break;
        if (halt.time_s && (report.cut || budget_used() >= *halt.time_s)) break;
        if (halt.target_error && report.spp >= kMinSppForErrorHalt && report.error.mean_rel_error <= *halt.target_error)
            break;
        // Aim for passes of about kPassSeconds so progress, checkpoints and halts stay responsive;
        // pass boundaries never change the image, only how often it is reported.
        long long fit = (long long)(kPassSeconds * report.samples_per_s / double(std::max<long long>(1, pixels)));
        long long cap = std::min(kMaxPassSpp, pass_spp * 2);
        pass_spp = std::clamp(fit, 1LL, cap);
    }
    return report;
}

}  // namespace omega
