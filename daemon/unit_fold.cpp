#include "daemon/unit_fold.h"

#include <fmt/format.h>

#include <cmath>
#include <set>
#include <sstream>
#include <stdexcept>

#include "daemon/render_worker.h"

namespace omega::daemon {

std::string unit_part_path(const JobPaths& jp, std::uint64_t unit) {
  return jp.dir + "/units/" + std::to_string(unit) + ".exr";
}

void init_fold(UnitFold& f, const JobPaths& jp, const std::string& name, const std::string& integrator,
               const std::string& sampler, std::uint64_t seed, const std::vector<std::string>& allowed_roots) {
  if (f.film) return;
  SceneDesc d = load_job_scene(jp, name, integrator, sampler, allowed_roots);
  f.desc = d.sensor.film;
  f.integrator = integrator_name(d.integrator.type);
  f.sampler = sampler_name(d.integrator.sampler);
  f.seed = seed;
  f.film.emplace(f.desc);  // merge_parts starts from an empty film too
  for (const AovDesc& a : f.desc.aovs) f.aovs.push_back({a.name, a.expr, Film(f.desc)});
}

namespace {

// The unit's AOVs and breakdown, folded like its film. AOVs are part of the image the job asked
// for: a unit without them fails the fold (and names what it holds). The breakdown is a report:
// without its sums the job ends without one and says so.
void fold_extras(UnitFold& f, const std::string& path, const PartialRender& p) {
  if (format_aov_list(p.aovs) != format_aov_list(f.aovs))
    throw std::runtime_error(path + ": the unit holds aovs [" + format_aov_list(p.aovs) + "], the job asks for [" +
                             format_aov_list(f.aovs) + "] (a worker older than the daemon?)");
  for (std::size_t i = 0; i < f.aovs.size(); ++i) f.aovs[i].film.merge(p.aovs[i].film);
  if (!f.desc.breakdown || f.breakdown_dropped) return;
  const auto it = p.meta.attributes.find("omega.breakdown_state");
  try {
    if (it == p.meta.attributes.end()) throw std::invalid_argument("the unit carries no omega.breakdown_state");
    merge_breakdown_state(f.breakdown, parse_breakdown_state(it->second));
  } catch (const std::invalid_argument& e) {
    f.breakdown.reset();
    f.breakdown_dropped = true;
    f.warnings.push_back("the path-class breakdown is left out: " + path + ": " + e.what());
  }
}

}  // namespace

PartialRender check_part(const UnitFold& f, const std::string& path, std::uint64_t begin, std::uint64_t end) {
  PartialRender p = read_partial_exr(path);
  const std::string want = format_ranges({{static_cast<long long>(begin), static_cast<long long>(end)}});
  if (format_ranges(p.part.ranges) != want)
    throw std::runtime_error("the part holds samples " + format_ranges(p.part.ranges) + ", not " + want);
  if (p.part.seed != f.seed) throw std::runtime_error("the part was rendered with seed " + std::to_string(p.part.seed));
  if (p.part.integrator != f.integrator) throw std::runtime_error("the part was rendered by " + p.part.integrator);
  if (p.part.sampler != f.sampler) throw std::runtime_error("the part was rendered with the " + p.part.sampler + " sampler");
  const Rect a = p.film.crop(), b = f.film->crop();
  if (p.film.width() != f.film->width() || p.film.height() != f.film->height() || a.x0 != b.x0 || a.y0 != b.y0 ||
      a.x1 != b.x1 || a.y1 != b.y1)
    throw std::runtime_error("the part's film differs from the job's");
  if (!f.scene_hash.empty() && p.part.scene_hash != f.scene_hash)
    throw std::runtime_error("the part's scene hash differs from the other units'");
  return p;
}

FoldUpdate fold_parts(UnitFold& f, std::uint64_t job, const std::vector<std::string>& paths, bool tiles,
                      int tile_size) {
  FoldUpdate u;
  u.job = job;
  try {
    for (const std::string& path : paths) {
      PartialRender p = read_partial_exr(path);
      const SampleRange r = p.part.ranges.front();
      if (p.part.ranges.size() != 1 || static_cast<std::uint64_t>(r.begin) != f.spp)
        throw std::runtime_error(path + ": holds samples " + format_ranges(p.part.ranges) + ", the fold is at " +
                                 std::to_string(f.spp));
      f.film->merge(p.film);
      fold_extras(f, path, p);
      f.spp = static_cast<std::uint64_t>(r.end);
      f.units += 1;
      f.time_s += p.meta.time_s;
      f.nonfinite += p.meta.nonfinite;
      if (f.scene_hash.empty()) f.scene_hash = p.part.scene_hash;
      std::set<std::string> seen(f.warnings.begin(), f.warnings.end());
      for (const std::string& w : p.meta.warnings)
        if (seen.insert(w).second) f.warnings.push_back(w);
    }
  } catch (const std::exception& e) {
    u.error = e.what();
    return u;
  }
  auto snap = std::make_shared<FilmSnapshot>();
  snap->spp = f.spp;
  snap->pass = f.units;
  snap->elapsed_s = f.time_s;
  snap->nonfinite = f.nonfinite;
  const ErrorEstimate e = f.film->estimate_error();
  if (std::isfinite(e.mean_rel_error)) snap->rel_error = e.mean_rel_error;
  snap->film = f.film->serialize();
  for (const AovFilm& a : f.aovs) snap->aov_films.push_back(a.film.serialize());
  snap->integrator = f.integrator;
  snap->seed = f.seed;
  if (f.breakdown) {
    snap->breakdown = breakdown_csv(make_breakdown_report(f.breakdown->stats, f.breakdown->region, f.breakdown->max_length));
    snap->breakdown_state = breakdown_state_text(*f.breakdown);
    snap->breakdown_samples = fmt::format("0:{}", f.spp);
  }
  if (tiles) u.tiles = encode_tiles(*f.film, tile_size, *snap, f.aovs);
  u.snapshot = std::move(snap);
  u.film = f.desc;
  return u;
}

void write_fold_result(const UnitFold& f, const std::string& path) {
  ExrMeta m;
  m.spp = static_cast<long long>(f.spp);
  m.time_s = f.time_s;
  m.integrator = f.integrator;
  m.seed = f.seed;
  m.attributes["omega.sampler"] = f.sampler;
  m.nonfinite = f.nonfinite;
  m.warnings = f.warnings;
  const ErrorEstimate e = f.film->estimate_error();
  m.rel_error = std::isfinite(e.mean_rel_error) ? e.mean_rel_error : 0;
  append_aov_layers(f.aovs, m);
  if (f.breakdown) {
    m.attributes["omega.breakdown"] =
        breakdown_csv(make_breakdown_report(f.breakdown->stats, f.breakdown->region, f.breakdown->max_length));
    m.attributes["omega.breakdown_samples"] = fmt::format("0:{}", f.spp);
    m.attributes["omega.breakdown_state"] = breakdown_state_text(*f.breakdown);
  }
  PartInfo part{{{0, static_cast<long long>(f.spp)}}, f.scene_hash, f.seed, f.integrator, f.sampler};
  write_partial_exr(path, *f.film, m, part, f.aovs);
}

std::string format_asset_list(const std::vector<protocol::AssetRef>& assets) {
  std::string out;
  for (const auto& a : assets) out += a.sha256 + " " + std::to_string(a.size) + " " + a.name + "\n";
  return out;
}

std::vector<protocol::AssetRef> parse_asset_list(const std::string& text) {
  std::vector<protocol::AssetRef> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    const auto a = line.find(' ');
    const auto b = a == std::string::npos ? a : line.find(' ', a + 1);
    if (b == std::string::npos) throw std::runtime_error("assets.txt: malformed line '" + line + "'");
    protocol::AssetRef r;
    r.sha256 = line.substr(0, a);
    r.size = std::stoull(line.substr(a + 1, b - a - 1));
    r.name = line.substr(b + 1);
    out.push_back(std::move(r));
  }
  return out;
}

}  // namespace omega::daemon
