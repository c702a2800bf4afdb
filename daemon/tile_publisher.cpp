#include "daemon/tile_publisher.h"

#include <algorithm>

namespace omega::daemon {

namespace {
std::uint64_t slot_of(const protocol::Rect& r) { return (std::uint64_t(r.y0) << 32) | r.x0; }
}  // namespace

void TilePublisher::send_tile(const Sub& s, std::uint64_t job, const TileState& t) {
  protocol::Tile msg;
  msg.id = s.id;
  msg.job = job;
  msg.rect = t.rect;
  msg.pass = t.pass;
  msg.spp = t.spp;
  msg.version = t.version;
  protocol::Frame f = protocol::encode(msg);  // empty payload: the EXR is shared, not copied
  sink_.send_coalesced(s.conn, CoalesceKey{s.id, job, slot_of(t.rect)}, f.header, t.exr);
}

void TilePublisher::send_progress(const Sub& s, const protocol::Progress& p) {
  protocol::Progress msg = p;
  msg.id = s.id;
  sink_.send_coalesced(s.conn, CoalesceKey{s.id, p.job, kProgressSlot}, protocol::encode(msg).header, nullptr);
}

void TilePublisher::subscribe(std::uint64_t job, std::uint64_t conn, std::uint64_t sub_id) {
  JobEntry& e = jobs_[job];
  Sub s{conn, sub_id};
  for (const auto& [slot, t] : e.tiles) send_tile(s, job, t);
  if (e.progress) send_progress(s, *e.progress);
  if (e.done) {
    protocol::Done d = *e.done;
    d.id = sub_id;
    sink_.send_frame(conn, protocol::encode(d));
    return;
  }
  e.subs.push_back(s);
}

bool TilePublisher::unsubscribe(std::uint64_t job, std::uint64_t conn, std::uint64_t sub_id) {
  auto it = jobs_.find(job);
  if (it == jobs_.end()) return false;
  auto& subs = it->second.subs;
  auto n = subs.size();
  std::erase_if(subs, [&](const Sub& s) { return s.conn == conn && s.id == sub_id; });
  return subs.size() != n;
}

void TilePublisher::drop_connection(std::uint64_t conn) {
  for (auto& [job, e] : jobs_) std::erase_if(e.subs, [&](const Sub& s) { return s.conn == conn; });
}

void TilePublisher::store_tile(std::uint64_t job, JobEntry& e, const EncodedTile& et, std::uint64_t pass,
                               std::uint64_t spp) {
  TileState& t = e.tiles[slot_of(et.rect)];
  if (t.exr && spp < t.version) return;  // a streamed tile is newer than its pass's boundary copy
  t.rect = et.rect;
  t.pass = pass;
  t.spp = spp;
  t.version = spp;
  t.exr = et.exr;
  for (const Sub& s : e.subs) send_tile(s, job, t);
}

void TilePublisher::update_tiles(std::uint64_t job, const std::vector<EncodedTile>& tiles, std::uint64_t pass,
                                 std::uint64_t spp) {
  JobEntry& e = jobs_[job];
  if (spp < e.tiles_spp || tiles.empty()) return;
  e.tiles_spp = spp;
  for (const EncodedTile& et : tiles) store_tile(job, e, et, pass, spp);
}

void TilePublisher::update_tile(std::uint64_t job, const EncodedTile& tile, std::uint64_t pass, std::uint64_t spp) {
  JobEntry& e = jobs_[job];
  if (spp <= e.tiles_spp) return;
  store_tile(job, e, tile, pass, spp);
}

void TilePublisher::tiles_complete(std::uint64_t job, std::uint64_t spp) {
  JobEntry& e = jobs_[job];
  e.tiles_spp = std::max(e.tiles_spp, spp);
}

void TilePublisher::progress(std::uint64_t job, protocol::JobState state, const protocol::ProgressInfo& p) {
  JobEntry& e = jobs_[job];
  protocol::Progress msg;
  msg.job = job;
  msg.state = state;
  msg.progress = p;
  e.progress = msg;
  for (const Sub& s : e.subs) send_progress(s, msg);
}

void TilePublisher::done(std::uint64_t job, protocol::JobState state, const protocol::ProgressInfo& p,
                         std::optional<std::string> message) {
  JobEntry& e = jobs_[job];
  protocol::Done d;
  d.job = job;
  d.state = state;
  d.progress = p;
  d.message = std::move(message);
  e.done = d;
  e.progress.reset();
  for (const Sub& s : e.subs) {
    protocol::Done m = d;
    m.id = s.id;
    sink_.send_frame(s.conn, protocol::encode(m));
  }
  e.subs.clear();
}

void TilePublisher::forget(std::uint64_t job) { jobs_.erase(job); }

std::size_t TilePublisher::watchers(std::uint64_t job) const {
  auto it = jobs_.find(job);
  return it == jobs_.end() ? 0 : it->second.subs.size();
}

std::uint64_t TilePublisher::tiles_spp(std::uint64_t job) const {
  auto it = jobs_.find(job);
  return it == jobs_.end() ? 0 : it->second.tiles_spp;
}

bool TilePublisher::has_tiles(std::uint64_t job) const {
  auto it = jobs_.find(job);
  return it != jobs_.end() && !it->second.tiles.empty();
}

}  // namespace omega::daemon
