#include "protocol/messages.h"

#include <gtest/gtest.h>

#include <set>

#include "protocol/frame_decoder.h"
#include "protocol/tools/examples.h"

using namespace omega::protocol;

namespace {

DecodedFrame through_decoder(const Frame& f) {
  FrameDecoder d;
  d.feed(encode_frame(f));
  EXPECT_FALSE(d.failed()) << (d.failed() ? d.error()->message : "");
  auto out = d.next();
  EXPECT_TRUE(out.has_value());
  return out ? *out : DecodedFrame{};
}

Result<Message, DecodeError> decode_header(std::string_view header, std::string payload = {}) {
  auto p = parse_header(header);
  EXPECT_TRUE(p.ok()) << (p ? "" : p.message());
  if (!p) return fail(DecodeError::invalid_value, "unparsable");
  return decode_message(DecodedFrame{p->type, p->id, p->header, std::move(payload)});
}

DecodeError code_of(std::string_view header) {
  auto r = decode_header(header);
  EXPECT_FALSE(r.ok()) << header;
  return r ? DecodeError::wrong_message_type : r.code();
}

}  // namespace

TEST(Messages, EveryExampleRoundTrips) {
  std::set<MessageType> seen;
  for (const auto& e : examples::all()) {
    Frame f = encode(e.message);
    auto m = decode_message(through_decoder(f));
    ASSERT_TRUE(m.ok()) << e.title << ": " << m.message();
    EXPECT_EQ(*m, e.message) << e.title;
    EXPECT_EQ(encode(*m), f) << e.title;
    seen.insert(type_of(e.message));
  }
  EXPECT_EQ(seen.size(), kMessageTypeCount) << "an example is missing for some message type";
}

TEST(Messages, OptionalFieldsAbsentAndPresent) {
  Submit s;
  s.id = 1;
  for (int mask = 0; mask < 8; ++mask) {
    s.halt = Halt{};
    if (mask & 1) s.halt.spp = 1;
    if (mask & 2) s.halt.time_s = 0.5;
    if (mask & 4) s.halt.target_error = 1e-5;
    auto m = decode<Submit>(through_decoder(encode(s)));
    ASSERT_TRUE(m.ok()) << m.message();
    EXPECT_EQ(*m, s);
  }
  s.sampler = "independent";
  auto with_sampler = decode<Submit>(through_decoder(encode(s)));
  ASSERT_TRUE(with_sampler.ok()) << with_sampler.message();
  EXPECT_EQ(*with_sampler, s);
  Done d{3, 4, JobState::failed, {}, std::string("out of memory\n\"quoted\" é")};
  auto r = decode<Done>(through_decoder(encode(d)));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(*r, d);
}

TEST(Messages, ExtremeValuesRoundTrip) {
  Accepted a{UINT64_MAX, UINT64_MAX};
  auto r = decode<Accepted>(through_decoder(encode(a)));
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(*r, a);
  Progress p;
  p.progress.elapsed_s = 1.7976931348623157e308;
  p.progress.rel_error = 5e-324;
  p.progress.samples_per_s = 0.1 + 0.2;
  auto q = decode<Progress>(through_decoder(encode(p)));
  ASSERT_TRUE(q.ok()) << q.message();
  EXPECT_EQ(*q, p);
  SetPriority sp{1, 2, kMinPriority};
  EXPECT_EQ(*decode<SetPriority>(through_decoder(encode(sp))), sp);
}

TEST(Messages, WrongTypeIsNamed) {
  auto f = through_decoder(encode(Ping{1}));
  auto r = decode<Pong>(f);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.code(), DecodeError::wrong_message_type);
}

TEST(Messages, FieldValidation) {
  EXPECT_EQ(code_of(R"({"type": "hello", "id": 1, "min_version": 1, "client": "x"})"), DecodeError::missing_field);
  EXPECT_EQ(code_of(R"({"type": "hello", "id": 1, "version": "1", "min_version": 1, "client": "x"})"), DecodeError::wrong_type);
  EXPECT_EQ(code_of(R"({"type": "hello", "id": 1, "version": 0, "min_version": 1, "client": "x"})"), DecodeError::out_of_range);
  EXPECT_EQ(code_of(R"({"type": "hello", "id": 1, "version": 1, "min_version": 2, "client": "x"})"), DecodeError::out_of_range);
  EXPECT_EQ(code_of(R"({"type": "hello", "id": 1, "version": 1.5, "min_version": 1, "client": "x"})"), DecodeError::wrong_type);
  EXPECT_EQ(code_of(R"({"type": "welcome", "id": 1, "version": 1, "server": "s", "auth": "hmac-sha256"})"), DecodeError::missing_field);
  EXPECT_EQ(code_of(R"({"type": "welcome", "id": 1, "version": 1, "server": "s", "auth": "magic"})"), DecodeError::invalid_value);
  EXPECT_EQ(code_of(R"({"type": "auth", "id": 1, "user": "a", "mac": "ABCD"})"), DecodeError::invalid_value);
  EXPECT_EQ(code_of(R"({"type": "status", "id": 1, "job": -4})"), DecodeError::wrong_type);
  EXPECT_EQ(code_of(R"({"type": "status", "id": 1, "job": [1]})"), DecodeError::wrong_type);
  EXPECT_EQ(code_of(R"({"type": "set_priority", "id": 1, "job": 1, "priority": 1001})"), DecodeError::out_of_range);
  EXPECT_EQ(code_of(R"({"type": "submit", "id": 1, "name": "", "priority": 0, "halt": {"spp": 0}, "seed": 0, "assets": []})"), DecodeError::out_of_range);
  EXPECT_EQ(code_of(R"({"type": "submit", "id": 1, "name": "", "priority": 0, "halt": {"time_s": .nan}, "seed": 0, "assets": []})"), DecodeError::wrong_type);
  EXPECT_EQ(code_of(R"({"type": "submit", "id": 1, "name": "", "priority": 0, "halt": {"time_s": 0}, "seed": 0, "assets": []})"), DecodeError::out_of_range);
  EXPECT_EQ(code_of(R"({"type": "submit", "id": 1, "name": "", "priority": 0, "halt": 5, "seed": 0, "assets": []})"), DecodeError::wrong_type);
  EXPECT_EQ(code_of(R"({"type": "submit", "id": 1, "name": "", "priority": 0, "halt": {}, "seed": 0, "integrator": "Path!", "assets": []})"), DecodeError::invalid_value);
  const std::string sha(64, 'a');
  for (std::string bad : std::vector<std::string>{"/etc/passwd", "../x", "a/../b", "a//b", "a/", "./a", std::string(256, 'a') + "/m.obj",
                                                    [] { std::string n; for (int i = 0; i < 5; ++i) n += std::string(250, 'a') + "/"; return n + "m.obj"; }()}) {
    std::string h = R"({"type": "submit", "id": 1, "name": "", "priority": 0, "halt": {}, "seed": 0, "assets": [{"name": ")" +
                    bad + R"(", "sha256": ")" + sha + R"(", "size": 1}]})";
    EXPECT_EQ(code_of(h), DecodeError::invalid_value) << bad;
  }
  // A component of 255 bytes is a valid file name; a name that is also another's folder is not.
  auto two = [&](const std::string& a, const std::string& b) {
    return R"({"type": "submit", "id": 1, "name": "", "priority": 0, "halt": {}, "seed": 0, "assets": [{"name": ")" + a +
           R"(", "sha256": ")" + sha + R"(", "size": 1}, {"name": ")" + b + R"(", "sha256": ")" + sha + R"(", "size": 1}]})";
  };
  EXPECT_EQ(code_of(two("a/m.obj", "a")), DecodeError::invalid_value);
  EXPECT_EQ(code_of(two("a", "a/b/m.obj")), DecodeError::invalid_value);
  EXPECT_TRUE(decode_header(two(std::string(255, 'a'), "a-b/m.obj")).ok());
  EXPECT_EQ(code_of(R"({"type": "tile", "id": 1, "job": 1, "rect": [4, 0, 4, 8], "pass": 1, "spp": 1, "version": 1})"), DecodeError::invalid_value);
  EXPECT_EQ(code_of(R"({"type": "tile", "id": 1, "job": 1, "rect": [0, 0, 4], "pass": 1, "spp": 1, "version": 1})"), DecodeError::wrong_type);
  EXPECT_EQ(code_of(R"({"type": "done", "id": 1, "job": 1, "state": "running", "progress": {"pass": 1, "spp": 1, "elapsed_s": 1, "samples_per_s": 1}})"), DecodeError::invalid_value);
  EXPECT_EQ(code_of(R"({"type": "progress", "id": 1, "job": 1, "state": "running", "progress": {"pass": 1, "spp": 1, "elapsed_s": -1, "samples_per_s": 1}})"), DecodeError::out_of_range);
  EXPECT_EQ(code_of(R"({"type": "need_assets", "id": 1, "missing": ["xyz"]})"), DecodeError::invalid_value);
}

TEST(Messages, ErrorMessagesNameTheField) {
  auto r = decode_header(R"({"type": "job_list", "id": 1, "jobs": [{"job": 1, "name": "", "state": "queued", "priority": 0, "owner": "o", "halt": {}, "progress": {"pass": 0, "spp": "x", "elapsed_s": 0, "samples_per_s": 0}}]})");
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.message().find("jobs[0].progress.spp"), std::string::npos) << r.message();
}

TEST(Messages, UnknownFieldsAreIgnoredAndUnknownErrorCodesKept) {
  auto r = decode_header(R"({"type": "status", "id": 1, "job": 2, "future": {"x": 1}})");
  ASSERT_TRUE(r.ok());
  auto e = decode_header(R"({"type": "error", "id": 1, "code": "from_the_future", "message": "m"})");
  ASSERT_TRUE(e.ok());
  EXPECT_EQ(std::get<Error>(*e).code, ErrorCode::unknown);
}

// fuzz_messages' finding: "\N" (YAML's escape for U+0085) unescaped to a bare 0x85 byte, which
// the decoder kept and our encoder then wrote into a frame no peer could read.
TEST(Messages, StringsThatUnescapeToInvalidUtf8AreRefused) {
  auto r = decode_header(R"({"type": "error", "id": 3, "code": "scene_invalid", "message": "a\NULL b"})");
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.code(), DecodeError::invalid_value);
  EXPECT_NE(r.message().find("message"), std::string::npos) << r.message();
  auto ok = decode_header(R"({"type": "error", "id": 3, "code": "scene_invalid", "message": "a\u0085 b"})");
  ASSERT_TRUE(ok.ok()) << ok.message();
  auto again = decode_message(through_decoder(encode(*ok)));
  ASSERT_TRUE(again.ok());
  EXPECT_TRUE(*again == *ok);
}

TEST(Messages, PayloadOnlyWhereAllowed) {
  auto p = parse_header(R"({"type": "ping", "id": 1})");
  ASSERT_TRUE(p.ok());
  auto r = decode_message(DecodedFrame{p->type, p->id, p->header, "x"});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.code(), DecodeError::invalid_value);
}

TEST(Version, Negotiation) {
  EXPECT_EQ(negotiate_version(1, 1, 1, 1), 1u);
  EXPECT_EQ(negotiate_version(1, 3, 1, 2), 2u);
  EXPECT_EQ(negotiate_version(2, 5, 1, 3), 3u);
  EXPECT_FALSE(negotiate_version(4, 5, 1, 3).has_value());
  EXPECT_FALSE(negotiate_version(1, 1, 2, 3).has_value());
}

TEST(Auth, SignedTextLayout) {
  EXPECT_EQ(auth_signed_text("00ff", "alice"), "omega-auth-v1\n00ff\nalice");
}

TEST(Messages, WorkerMessagesCheckTheirFields) {
  // A unit's range must be non-empty; threads at least 1; worker lists only in job fields.
  EXPECT_EQ(code_of(R"({"type": "unit_result", "id": 1, "job": 1, "unit": 0, "begin": 4, "end": 4, "time_s": 0, "samples_per_s": 0})"),
            DecodeError::invalid_value);
  EXPECT_EQ(code_of(R"({"type": "work_request", "id": 1, "threads": 0, "name": ""})"), DecodeError::out_of_range);
  EXPECT_EQ(code_of(R"({"type": "asset_request", "id": 1, "job": 1, "sha256": "abc"})"), DecodeError::invalid_value);
  // unit_result and work_unit carry payloads; unit_stop none.
  EXPECT_TRUE(carries_payload(MessageType::unit_result));
  EXPECT_TRUE(carries_payload(MessageType::work_unit));
  EXPECT_FALSE(carries_payload(MessageType::unit_stop));
}

TEST(Messages, SubmitWorkersAndJobInfoWorkersRoundTrip) {
  Submit s;
  s.id = 3;
  s.workers = 4;
  s.unit_spp = 32;
  auto m = decode<Submit>(through_decoder(encode(s)));
  ASSERT_TRUE(m.ok()) << m.message();
  EXPECT_EQ(*m, s);
  s.workers.reset();
  s.unit_spp.reset();
  EXPECT_EQ(encode(s).header.find("workers"), std::string::npos) << "a local job's submit is as before";
  JobInfoReply r;
  r.id = 2;
  r.info.job = 9;
  r.info.workers.push_back(WorkerInfo{"conn 4 (node1:77)", 3, {"96:128"}, 2.5e6});
  r.info.workers.push_back(WorkerInfo{"conn 5 (node2:78)", 0, {}, 0});
  auto j = decode<JobInfoReply>(through_decoder(encode(r)));
  ASSERT_TRUE(j.ok()) << j.message();
  EXPECT_EQ(*j, r);
}
