// What a subscription or a fetch sends back: tile, progress, done, image.
#include "protocol/messages_common.h"

namespace omega::protocol {

using detail::begin_header;
using detail::check_frame;
using detail::finish;
using detail::finish_decode;

namespace {
constexpr std::uint64_t kMaxPixels = 1u << 30;  // per axis; far past any real film
}

Frame encode(const Tile& m) {
  auto w = begin_header(MessageType::tile, m.id);
  w.field_u("job", m.job).key("rect").begin_list();
  w.u64(m.rect.x0).u64(m.rect.y0).u64(m.rect.x1).u64(m.rect.y1).end_list();
  w.field_u("pass", m.pass).field_u("spp", m.spp).field_u("version", m.version);
  return finish(w, m.exr);
}

template <>
Result<Tile, DecodeError> decode<Tile>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::tile)) return *e;
  FieldReader r(f.header);
  Tile m;
  m.id = f.id;
  m.job = r.u64("job");
  auto rect = r.u64_list("rect", 4, kMaxPixels);
  if (r.ok()) {
    m.rect = Rect{static_cast<std::uint32_t>(rect[0]), static_cast<std::uint32_t>(rect[1]),
                  static_cast<std::uint32_t>(rect[2]), static_cast<std::uint32_t>(rect[3])};
    if (m.rect.x0 >= m.rect.x1 || m.rect.y0 >= m.rect.y1)
      r.fail(DecodeError::invalid_value, "rect", "must satisfy x0 < x1 and y0 < y1");
  }
  m.pass = r.u64("pass");
  m.spp = r.u64("spp");
  m.version = r.u64("version");
  m.exr = f.payload;
  return finish_decode(r, std::move(m));
}

Frame encode(const Progress& m) {
  auto w = begin_header(MessageType::progress, m.id);
  w.field_u("job", m.job).field("state", to_string(m.state)).key("progress");
  detail::write_progress(w, m.progress);
  return finish(w);
}

template <>
Result<Progress, DecodeError> decode<Progress>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::progress)) return *e;
  FieldReader r(f.header);
  Progress m;
  m.id = f.id;
  m.job = r.u64("job");
  m.state = detail::read_job_state(r, "state");
  m.progress = detail::read_progress(r);
  return finish_decode(r, std::move(m));
}

Frame encode(const Done& m) {
  auto w = begin_header(MessageType::done, m.id);
  w.field_u("job", m.job).field("state", to_string(m.state)).key("progress");
  detail::write_progress(w, m.progress);
  if (m.message) w.field("message", *m.message);
  return finish(w);
}

template <>
Result<Done, DecodeError> decode<Done>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::done)) return *e;
  FieldReader r(f.header);
  Done m;
  m.id = f.id;
  m.job = r.u64("job");
  m.state = detail::read_job_state(r, "state");
  if (r.ok() && m.state != JobState::done && m.state != JobState::failed && m.state != JobState::cancelled)
    r.fail(DecodeError::invalid_value, "state", "a finished job is done, failed or cancelled");
  m.progress = detail::read_progress(r);
  m.message = r.opt_str("message", kMaxMessageBytes);
  return finish_decode(r, std::move(m));
}

Frame encode(const Image& m) {
  auto w = begin_header(MessageType::image, m.id);
  w.field_u("job", m.job).field_u("pass", m.pass).field_u("spp", m.spp);
  w.field_u("width", m.width).field_u("height", m.height);
  return finish(w, m.exr);
}

template <>
Result<Image, DecodeError> decode<Image>(const DecodedFrame& f) {
  if (auto e = check_frame(f, MessageType::image)) return *e;
  FieldReader r(f.header);
  Image m;
  m.id = f.id;
  m.job = r.u64("job");
  m.pass = r.u64("pass");
  m.spp = r.u64("spp");
  m.width = static_cast<std::uint32_t>(r.u64("width", 1, kMaxPixels));
  m.height = static_cast<std::uint32_t>(r.u64("height", 1, kMaxPixels));
  m.exr = f.payload;
  return finish_decode(r, std::move(m));
}

}  // namespace omega::protocol
