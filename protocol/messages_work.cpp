// The worker messages (omega worker <-> omegad): work_request, work_unit, asset_request,
// unit_result, unit_stop. docs/protocol.md "Workers".
#include "protocol/messages_common.h"

namespace omega::protocol {

using detail::begin_header;
using detail::check_frame;
using detail::finish;
using detail::finish_decode;

namespace {
constexpr double kHugeRate = 1e300;
// The unit a work_unit or unit_result names: job, unit, and its range, begin < end, within the
// spp any daemon accepts.
template <class M>
void read_unit(FieldReader& r, M& m) {
  m.job = r.u64("job");
  m.unit = r.u64("unit");
  m.begin = r.u64("begin", 0, 1ull << 40);
  m.end = r.u64("end", 1, 1ull << 40);
  if (r.ok() && m.begin >= m.end) r.fail(DecodeError::invalid_value, "end", "must be greater than begin");
}
}  // namespace

Frame encode(const WorkRequest& m) {
  auto w = begin_header(MessageType::work_request, m.id);
  w.field_u("threads", m.threads).field("name", m.name);
  return finish(w);
}

template <>
Result<WorkRequest, DecodeError> decode<WorkRequest>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::work_request)) return *e;
  FieldReader r(f.header);
  WorkRequest m;
  m.id = f.id;
  m.threads = static_cast<std::uint32_t>(r.u64("threads", 1, kMaxWorkerThreads));
  m.name = r.str("name", 256);
  return finish_decode(r, std::move(m));
}

Frame encode(const WorkUnit& m) {
  auto w = begin_header(MessageType::work_unit, m.id);
  w.field_u("job", m.job).field_u("unit", m.unit).field_u("begin", m.begin).field_u("end", m.end);
  w.field_u("seed", m.seed).field("name", m.name);
  if (m.integrator) w.field("integrator", *m.integrator);
  if (m.sampler) w.field("sampler", *m.sampler);
  detail::write_assets(w, m.assets);
  return finish(w, m.scene);
}

template <>
Result<WorkUnit, DecodeError> decode<WorkUnit>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::work_unit)) return *e;
  FieldReader r(f.header);
  WorkUnit m;
  m.id = f.id;
  read_unit(r, m);
  m.seed = r.u64("seed");
  m.name = r.str("name", kMaxNameBytes);
  m.integrator = detail::read_identifier(r, "integrator");
  m.sampler = detail::read_identifier(r, "sampler");
  m.assets = detail::read_assets(r);
  m.scene = f.payload;
  return finish_decode(r, std::move(m));
}

Frame encode(const AssetRequest& m) {
  auto w = begin_header(MessageType::asset_request, m.id);
  w.field_u("job", m.job).field("sha256", m.sha256);
  return finish(w);
}

template <>
Result<AssetRequest, DecodeError> decode<AssetRequest>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::asset_request)) return *e;
  FieldReader r(f.header);
  AssetRequest m;
  m.id = f.id;
  m.job = r.u64("job");
  m.sha256 = detail::read_sha256(r, "sha256");
  return finish_decode(r, std::move(m));
}

Frame encode(const UnitResult& m) {
  auto w = begin_header(MessageType::unit_result, m.id);
  w.field_u("job", m.job).field_u("unit", m.unit).field_u("begin", m.begin).field_u("end", m.end);
  w.field_f("time_s", m.time_s).field_f("samples_per_s", m.samples_per_s);
  return finish(w, m.part);
}

template <>
Result<UnitResult, DecodeError> decode<UnitResult>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::unit_result)) return *e;
  FieldReader r(f.header);
  UnitResult m;
  m.id = f.id;
  read_unit(r, m);
  m.time_s = r.f64("time_s", 0, 1e9);
  m.samples_per_s = r.f64("samples_per_s", 0, kHugeRate);
  m.part = f.payload;
  return finish_decode(r, std::move(m));
}

Frame encode(const UnitStop& m) {
  auto w = begin_header(MessageType::unit_stop, m.id);
  w.field_u("job", m.job).field_u("unit", m.unit).field("reason", m.reason);
  return finish(w);
}

template <>
Result<UnitStop, DecodeError> decode<UnitStop>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::unit_stop)) return *e;
  FieldReader r(f.header);
  UnitStop m;
  m.id = f.id;
  m.job = r.u64("job");
  m.unit = r.u64("unit");
  m.reason = r.str("reason", 256);
  return finish_decode(r, std::move(m));
}

}  // namespace omega::protocol
