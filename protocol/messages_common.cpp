#include "protocol/messages_common.h"

#include <limits>

namespace omega::protocol {

namespace {
constexpr double kHuge = std::numeric_limits<double>::max();
constexpr std::array<std::string_view, 3> kAuthNames{"none", "peer", "hmac-sha256"};
constexpr std::array<std::string_view, 6> kStateNames{"queued", "running", "paused",
                                                      "done",   "failed",  "cancelled"};
}  // namespace

std::string_view to_string(AuthMethod a) { return kAuthNames.at(static_cast<std::size_t>(a)); }
std::string_view to_string(JobState s) { return kStateNames.at(static_cast<std::size_t>(s)); }

bool is_lower_hex(std::string_view s) {
  for (char c : s)
    if (!((c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'))) return false;
  return true;
}

bool is_sha256_hex(std::string_view s) { return s.size() == 64 && is_lower_hex(s); }

std::string auth_signed_text(std::string_view nonce_hex, std::string_view user) {
  std::string s = "omega-auth-v1\n";
  s += nonce_hex;
  s += '\n';
  s += user;
  return s;
}

std::optional<std::uint32_t> negotiate_version(std::uint32_t client_min, std::uint32_t client_max,
                                               std::uint32_t server_min, std::uint32_t server_max) {
  std::uint32_t hi = std::min(client_max, server_max);
  std::uint32_t lo = std::max(client_min, server_min);
  if (hi < lo) return std::nullopt;
  return hi;
}

namespace detail {

HeaderWriter begin_header(MessageType t, std::uint64_t id) {
  HeaderWriter w;
  w.begin_map().field("type", to_string(t)).field_u("id", id);
  return w;
}

Frame finish(HeaderWriter& w, std::string payload) {
  w.end_map();
  return Frame{w.take(), std::move(payload)};
}

std::optional<Failure<DecodeError>> check_frame(const DecodedFrame& f, MessageType expected) {
  if (f.type != expected)
    return Failure<DecodeError>{DecodeError::wrong_message_type,
                                "expected a " + std::string(to_string(expected)) + " frame, got " +
                                    std::string(to_string(f.type))};
  if (!carries_payload(f.type) && !f.payload.empty())
    return Failure<DecodeError>{DecodeError::invalid_value,
                                std::string(to_string(f.type)) + " frames carry no payload"};
  return std::nullopt;
}

void write_halt(HeaderWriter& w, const Halt& h) {
  w.begin_map();
  if (h.spp) w.field_u("spp", *h.spp);
  if (h.time_s) w.field_f("time_s", *h.time_s);
  if (h.target_error) w.field_f("target_error", *h.target_error);
  w.end_map();
}

void write_progress(HeaderWriter& w, const ProgressInfo& p) {
  w.begin_map().field_u("pass", p.pass).field_u("spp", p.spp).field_f("elapsed_s", p.elapsed_s);
  if (p.rel_error) w.field_f("rel_error", *p.rel_error);
  w.field_f("samples_per_s", p.samples_per_s).end_map();
}

void write_job_info_fields(HeaderWriter& w, const JobInfo& j) {
  w.field_u("job", j.job).field("name", j.name).field("state", to_string(j.state));
  w.field_i("priority", j.priority).field("owner", j.owner);
  w.key("halt");
  write_halt(w, j.halt);
  w.key("progress");
  write_progress(w, j.progress);
  if (!j.workers.empty()) write_worker_infos(w, j.workers);  // local jobs: as before
}

void write_worker_infos(HeaderWriter& w, const std::vector<WorkerInfo>& ws) {
  w.key("workers").begin_list();
  for (const WorkerInfo& i : ws) {
    w.begin_map().field("name", i.name).field_u("units_done", i.units_done).key("units").begin_list();
    for (const std::string& u : i.units) w.str(u);
    w.end_list().field_f("samples_per_s", i.samples_per_s).end_map();
  }
  w.end_list();
}

std::vector<WorkerInfo> read_worker_infos(FieldReader& r) {
  std::vector<WorkerInfo> out;
  if (!r.has("workers")) return out;
  for (FieldReader& f : r.map_list("workers", kMaxWorkers)) {
    WorkerInfo i;
    i.name = f.str("name", kMaxNameBytes);
    i.units_done = f.u64("units_done");
    i.units = f.str_list("units", 1024, 64);
    i.samples_per_s = f.f64("samples_per_s", 0, kHuge);
    out.push_back(std::move(i));
  }
  return out;
}

Halt read_halt(FieldReader& r) {
  FieldReader h = r.map("halt", false);
  Halt out;
  out.spp = h.opt_u64("spp", 1, 1ull << 40);
  out.time_s = h.opt_f64("time_s", 0, 1e9, true);
  out.target_error = h.opt_f64("target_error", 0, 1e6, true);
  return out;
}

ProgressInfo read_progress(FieldReader& r) {
  FieldReader p = r.map("progress");
  ProgressInfo out;
  out.pass = p.u64("pass");
  out.spp = p.u64("spp");
  out.elapsed_s = p.f64("elapsed_s", 0, kHuge);
  out.rel_error = p.opt_f64("rel_error", 0, kHuge);
  out.samples_per_s = p.f64("samples_per_s", 0, kHuge);
  return out;
}

JobState read_job_state(FieldReader& r, std::string_view key) {
  std::string s = r.str(key, 64);
  if (!r.ok()) return JobState::queued;
  for (std::size_t i = 0; i < kStateNames.size(); ++i)
    if (kStateNames[i] == s) return static_cast<JobState>(i);
  r.fail(DecodeError::invalid_value, r.path_of(key),
         "'" + s + "' is not one of queued|running|paused|done|failed|cancelled");
  return JobState::queued;
}

JobInfo read_job_info_fields(FieldReader& r) {
  JobInfo j;
  j.job = r.u64("job");
  j.name = r.str("name", kMaxNameBytes);
  j.state = read_job_state(r, "state");
  j.priority = r.i64("priority", kMinPriority, kMaxPriority);
  j.owner = r.str("owner", kMaxNameBytes);
  j.halt = read_halt(r);
  j.progress = read_progress(r);
  j.workers = read_worker_infos(r);
  return j;
}

std::string read_sha256(FieldReader& r, std::string_view key) {
  std::string s = r.str(key, 64);
  if (r.ok() && !is_sha256_hex(s))
    r.fail(DecodeError::invalid_value, r.path_of(key), "expected 64 lowercase hex digits");
  return s;
}

}  // namespace detail
}  // namespace omega::protocol
