// submit and its asset exchange, job queries and job control.
#include <set>

#include "protocol/messages_common.h"

namespace omega::protocol {

using detail::begin_header;
using detail::check_frame;
using detail::finish;
using detail::finish_decode;

namespace {

// Asset names become paths under the daemon's job directory, so refuse anything that could
// leave it. The daemon still resolves them safely; this is the first line.
bool is_safe_asset_name(std::string_view s) {
  // 1024 bytes in all keeps STATE/jobs/ID/files/NAME well inside PATH_MAX.
  if (s.empty() || s.size() > 1024 || s.front() == '/' || s.back() == '/') return false;
  std::size_t start = 0;
  while (start <= s.size()) {
    std::size_t end = s.find('/', start);
    if (end == std::string_view::npos) end = s.size();
    std::string_view part = s.substr(start, end - start);
    if (part.empty() || part == "." || part == "..") return false;
    if (part.size() > 255) return false;  // NAME_MAX: the file could not be created
    start = end + 1;
  }
  return s.find('\0') == std::string_view::npos && s.find('\\') == std::string_view::npos;
}

bool is_identifier(std::string_view s) {
  if (s.empty() || s.size() > 64) return false;
  for (char c : s)
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) return false;
  return true;
}

}  // namespace

Frame encode(const Submit& m) {
  auto w = begin_header(MessageType::submit, m.id);
  w.field("name", m.name).field_i("priority", m.priority).key("halt");
  detail::write_halt(w, m.halt);
  w.field_u("seed", m.seed);
  if (m.integrator) w.field("integrator", *m.integrator);
  if (m.sampler) w.field("sampler", *m.sampler);  // absent: the scene's (older clients send none)
  detail::write_assets(w, m.assets);
  if (m.workers) w.field_u("workers", *m.workers);  // absent: a local job (older clients send none)
  if (m.unit_spp) w.field_u("unit_spp", *m.unit_spp);
  return finish(w, m.scene);
}

void detail::write_assets(HeaderWriter& w, const std::vector<AssetRef>& assets) {
  w.key("assets").begin_list();
  for (const AssetRef& a : assets)
    w.begin_map().field("name", a.name).field("sha256", a.sha256).field_u("size", a.size).end_map();
  w.end_list();
}

std::optional<std::string> detail::read_identifier(FieldReader& r, std::string_view key) {
  std::optional<std::string> v = r.opt_str(key, 64);
  if (r.ok() && v && !is_identifier(*v)) r.fail(DecodeError::invalid_value, r.path_of(key), "expected a name of [a-z0-9_]");
  return v;
}

std::vector<AssetRef> detail::read_assets(FieldReader& r) {
  std::vector<AssetRef> out;
  std::set<std::string> names;
  for (FieldReader& a : r.map_list("assets", kMaxAssets)) {
    AssetRef ref;
    ref.name = a.str("name", kMaxNameBytes);
    if (a.ok() && !is_safe_asset_name(ref.name))
      a.fail(DecodeError::invalid_value, a.path_of("name"),
             "must be a relative path of at most 1024 bytes without '.', '..' or empty components, each at most 255 bytes");
    if (a.ok() && !names.insert(ref.name).second)
      a.fail(DecodeError::invalid_value, a.path_of("name"), "'" + ref.name + "' is listed twice");
    ref.sha256 = detail::read_sha256(a, "sha256");
    ref.size = a.u64("size");
    out.push_back(std::move(ref));
  }
  // A name that is also another's folder ("a" and "a/b.obj") cannot be both a file and a folder.
  for (const std::string& n : names) {
    auto it = names.lower_bound(n + "/");
    if (r.ok() && it != names.end() && it->compare(0, n.size() + 1, n + "/") == 0)
      r.fail(DecodeError::invalid_value, "assets", "'" + n + "' is both an asset and the folder of '" + *it + "'");
  }
  return out;
}

template <>
Result<Submit, DecodeError> decode<Submit>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::submit)) return *e;
  FieldReader r(f.header);
  Submit m;
  m.id = f.id;
  m.name = r.str("name", kMaxNameBytes);
  m.priority = r.i64("priority", kMinPriority, kMaxPriority);
  m.halt = detail::read_halt(r);
  m.seed = r.u64("seed");
  m.integrator = detail::read_identifier(r, "integrator");
  m.sampler = detail::read_identifier(r, "sampler");
  m.assets = detail::read_assets(r);
  if (r.has("workers")) m.workers = static_cast<std::uint32_t>(r.u64("workers", 0, kMaxWorkers));
  m.unit_spp = r.opt_u64("unit_spp", 1, 1ull << 40);
  m.scene = f.payload;
  return finish_decode(r, std::move(m));
}

Frame encode(const NeedAssets& m) {
  auto w = begin_header(MessageType::need_assets, m.id);
  w.key("missing").begin_list();
  for (const std::string& h : m.missing) w.str(h);
  w.end_list();
  return finish(w);
}

template <>
Result<NeedAssets, DecodeError> decode<NeedAssets>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::need_assets)) return *e;
  FieldReader r(f.header);
  NeedAssets m;
  m.id = f.id;
  m.missing = r.str_list("missing", kMaxAssets, 64);
  for (std::size_t i = 0; r.ok() && i < m.missing.size(); ++i)
    if (!is_sha256_hex(m.missing[i]))
      r.fail(DecodeError::invalid_value, "missing[" + std::to_string(i) + "]",
             "expected 64 lowercase hex digits");
  return finish_decode(r, std::move(m));
}

Frame encode(const Asset& m) {
  auto w = begin_header(MessageType::asset, m.id);
  w.field("sha256", m.sha256);
  return finish(w, m.data);
}

template <>
Result<Asset, DecodeError> decode<Asset>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::asset)) return *e;
  FieldReader r(f.header);
  Asset m;
  m.id = f.id;
  m.sha256 = detail::read_sha256(r, "sha256");
  m.data = f.payload;
  return finish_decode(r, std::move(m));
}

Frame encode(const Accepted& m) {
  auto w = begin_header(MessageType::accepted, m.id);
  w.field_u("job", m.job);
  return finish(w);
}

template <>
Result<Accepted, DecodeError> decode<Accepted>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::accepted)) return *e;
  FieldReader r(f.header);
  Accepted m;
  m.id = f.id;
  m.job = r.u64("job");
  return finish_decode(r, std::move(m));
}

Frame encode(const Status& m) {
  auto w = begin_header(MessageType::status, m.id);
  w.field_u("job", m.job);
  return finish(w);
}

template <>
Result<Status, DecodeError> decode<Status>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::status)) return *e;
  FieldReader r(f.header);
  Status m;
  m.id = f.id;
  m.job = r.u64("job");
  return finish_decode(r, std::move(m));
}

Frame encode(const JobInfoReply& m) {
  auto w = begin_header(MessageType::job_info, m.id);
  detail::write_job_info_fields(w, m.info);
  return finish(w);
}

template <>
Result<JobInfoReply, DecodeError> decode<JobInfoReply>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::job_info)) return *e;
  FieldReader r(f.header);
  JobInfoReply m;
  m.id = f.id;
  m.info = detail::read_job_info_fields(r);
  return finish_decode(r, std::move(m));
}

Frame encode(const JobList& m) {
  auto w = begin_header(MessageType::job_list, m.id);
  w.key("jobs").begin_list();
  for (const JobInfo& j : m.jobs) {
    w.begin_map();
    detail::write_job_info_fields(w, j);
    w.end_map();
  }
  w.end_list();
  return finish(w);
}

template <>
Result<JobList, DecodeError> decode<JobList>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::job_list)) return *e;
  FieldReader r(f.header);
  JobList m;
  m.id = f.id;
  for (FieldReader& j : r.map_list("jobs", kMaxJobsListed)) m.jobs.push_back(detail::read_job_info_fields(j));
  return finish_decode(r, std::move(m));
}

template <MessageType T>
Frame encode(const JobRequest<T>& m) {
  auto w = begin_header(T, m.id);
  w.field_u("job", m.job);
  return finish(w);
}

namespace {
template <MessageType T>
Result<JobRequest<T>, DecodeError> decode_job_request(const DecodedFrame& f) {
  if (auto e = check_frame(f, T)) return *e;
  FieldReader r(f.header);
  JobRequest<T> m;
  m.id = f.id;
  m.job = r.u64("job");
  return finish_decode(r, std::move(m));
}
}  // namespace

template Frame encode(const JobRequest<MessageType::cancel>&);
template Frame encode(const JobRequest<MessageType::pause>&);
template Frame encode(const JobRequest<MessageType::resume>&);
template Frame encode(const JobRequest<MessageType::delete_job>&);
template Frame encode(const JobRequest<MessageType::subscribe>&);
template Frame encode(const JobRequest<MessageType::unsubscribe>&);
template Frame encode(const JobRequest<MessageType::fetch>&);

template <>
Result<Cancel, DecodeError> decode<Cancel>(const DecodedFrame& f) { return decode_job_request<MessageType::cancel>(f); }
template <>
Result<Pause, DecodeError> decode<Pause>(const DecodedFrame& f) { return decode_job_request<MessageType::pause>(f); }
template <>
Result<Resume, DecodeError> decode<Resume>(const DecodedFrame& f) { return decode_job_request<MessageType::resume>(f); }
template <>
Result<Delete, DecodeError> decode<Delete>(const DecodedFrame& f) { return decode_job_request<MessageType::delete_job>(f); }
template <>
Result<Subscribe, DecodeError> decode<Subscribe>(const DecodedFrame& f) { return decode_job_request<MessageType::subscribe>(f); }
template <>
Result<Unsubscribe, DecodeError> decode<Unsubscribe>(const DecodedFrame& f) { return decode_job_request<MessageType::unsubscribe>(f); }
template <>
Result<Fetch, DecodeError> decode<Fetch>(const DecodedFrame& f) { return decode_job_request<MessageType::fetch>(f); }

Frame encode(const SetPriority& m) {
  auto w = begin_header(MessageType::set_priority, m.id);
  w.field_u("job", m.job).field_i("priority", m.priority);
  return finish(w);
}

template <>
Result<SetPriority, DecodeError> decode<SetPriority>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::set_priority)) return *e;
  FieldReader r(f.header);
  SetPriority m;
  m.id = f.id;
  m.job = r.u64("job");
  m.priority = r.i64("priority", kMinPriority, kMaxPriority);
  return finish_decode(r, std::move(m));
}

}  // namespace omega::protocol
