#include "protocol/frame_decoder.h"

#include <gtest/gtest.h>

#include <random>

#include "protocol/messages.h"
#include "protocol/tools/examples.h"

using namespace omega::protocol;

namespace {

std::string all_examples_stream() {
  std::string s;
  for (const auto& e : examples::all()) append_frame(s, encode(e.message));
  return s;
}

std::vector<Frame> reencode_all(FrameDecoder& d) {
  std::vector<Frame> out;
  while (auto f = d.next()) {
    auto m = decode_message(*f);
    EXPECT_TRUE(m.ok()) << (m ? "" : m.message());
    if (m) out.push_back(encode(*m));
  }
  return out;
}

std::vector<Frame> expected_frames() {
  std::vector<Frame> v;
  for (const auto& e : examples::all()) v.push_back(encode(e.message));
  return v;
}

// Feeds everything, pulling frames whenever the ready queue makes feed() pause.
std::vector<Frame> feed_all(FrameDecoder& d, std::string_view bytes, std::vector<Frame>& got) {
  while (!bytes.empty() && !d.failed()) {
    std::size_t n = d.feed(bytes);
    bytes.remove_prefix(n);
    for (auto& f : reencode_all(d)) got.push_back(std::move(f));
  }
  return got;
}

std::string raw_frame(std::string_view header, std::uint64_t payload_len, std::string_view payload = {}) {
  auto p = encode_prelude(static_cast<std::uint32_t>(header.size()), payload_len);
  return std::string(reinterpret_cast<const char*>(p.data()), p.size()) + std::string(header) +
         std::string(payload);
}

FrameError error_of(std::string_view bytes, DecoderLimits limits = {}) {
  FrameDecoder d(limits);
  d.feed(bytes);
  EXPECT_TRUE(d.failed());
  return d.failed() ? d.error()->code : FrameError::truncated;
}

}  // namespace

TEST(FrameDecoder, EverySplitPointOfAMultiFrameStream) {
  const std::string stream = all_examples_stream();
  const auto want = expected_frames();
  for (std::size_t cut = 0; cut <= stream.size(); ++cut) {
    FrameDecoder d;
    std::vector<Frame> got;
    feed_all(d, std::string_view(stream).substr(0, cut), got);
    feed_all(d, std::string_view(stream).substr(cut), got);
    ASSERT_FALSE(d.failed()) << "cut " << cut << ": " << d.error()->message;
    ASSERT_EQ(got, want) << "cut at " << cut;
    EXPECT_TRUE(d.at_frame_boundary());
  }
}

TEST(FrameDecoder, ByteByByte) {
  const std::string stream = all_examples_stream();
  FrameDecoder d;
  std::vector<Frame> got;
  for (char c : stream) feed_all(d, std::string_view(&c, 1), got);
  EXPECT_EQ(got, expected_frames());
  d.finish();
  EXPECT_FALSE(d.failed());
}

TEST(FrameDecoder, RandomSplits) {
  const std::string stream = all_examples_stream();
  std::mt19937 rng(1);
  for (int iter = 0; iter < 200; ++iter) {
    FrameDecoder d;
    std::vector<Frame> got;
    std::size_t pos = 0;
    while (pos < stream.size()) {
      std::size_t n = std::uniform_int_distribution<std::size_t>(1, 300)(rng);
      n = std::min(n, stream.size() - pos);
      feed_all(d, std::string_view(stream).substr(pos, n), got);
      pos += n;
    }
    ASSERT_EQ(got, expected_frames());
  }
}

TEST(FrameDecoder, PausesWhenReadyQueueIsFull) {
  DecoderLimits lim;
  lim.max_ready_frames = 2;
  FrameDecoder d(lim);
  std::string s;
  for (int i = 0; i < 5; ++i) append_frame(s, encode(Ping{static_cast<std::uint64_t>(i)}));
  std::size_t used = d.feed(s);
  EXPECT_EQ(d.ready_frames(), 2u);
  EXPECT_LT(used, s.size());
  EXPECT_EQ(d.next()->id, 0u);
}

TEST(FrameDecoder, BadMagicAtFirstWrongByte) {
  FrameDecoder d;
  EXPECT_EQ(d.feed(std::string_view("OMX1")), 2u);
  ASSERT_TRUE(d.failed());
  EXPECT_EQ(d.error()->code, FrameError::bad_magic);
  EXPECT_EQ(error_of("GET / HTTP/1.1\r\n\r\n"), FrameError::bad_magic);
}

TEST(FrameDecoder, HeaderTooLarge) {
  DecoderLimits lim;
  lim.max_header_bytes = 100;
  EXPECT_EQ(error_of(raw_frame(std::string(101, ' '), 0), lim), FrameError::header_too_large);
  // A claim of 4 GiB is refused from the prelude alone, before any header byte arrives.
  auto p = encode_prelude(0xffffffffu, 0);
  EXPECT_EQ(error_of(std::string(reinterpret_cast<const char*>(p.data()), p.size())),
            FrameError::header_too_large);
}

TEST(FrameDecoder, HugePayloadClaimRefusedWithoutAllocating) {
  // 2^60 bytes could never be allocated: reaching the error at all shows no allocation was tried.
  auto p = encode_prelude(2, 1ull << 60);
  FrameDecoder d;
  d.feed(std::span<const std::uint8_t>(p.data(), p.size()));
  ASSERT_TRUE(d.failed());
  EXPECT_EQ(d.error()->code, FrameError::payload_too_large);
}

TEST(FrameDecoder, PerTypeLimitsCheckedAfterHeaderBeforePayload) {
  // A ping may not carry a payload at all.
  EXPECT_EQ(error_of(raw_frame(encode(Ping{1}).header, 1)), FrameError::payload_too_large_for_type);
  DecoderLimits lim;
  lim.set_payload_limit(MessageType::tile, 10);
  Tile t;
  t.rect = Rect{0, 0, 1, 1};
  FrameDecoder d(lim);
  std::string hdr = encode(t).header;
  // Only the prelude and header are fed: the payload is refused before any of it arrives.
  d.feed(raw_frame(hdr, 11));
  ASSERT_TRUE(d.failed());
  EXPECT_EQ(d.error()->code, FrameError::payload_too_large_for_type);
  t.exr = std::string(10, 'e');
  FrameDecoder ok(lim);
  ok.feed(encode_frame(encode(t)));
  EXPECT_FALSE(ok.failed());
  EXPECT_EQ(ok.ready_frames(), 1u);
}

TEST(FrameDecoder, NamedHeaderErrors) {
  EXPECT_EQ(error_of(raw_frame("{\"type\": \"ping\", \"id\": 1", 0)), FrameError::header_not_yaml);
  EXPECT_EQ(error_of(raw_frame("[1, 2]", 0)), FrameError::header_not_mapping);
  EXPECT_EQ(error_of(raw_frame("", 0)), FrameError::header_not_mapping);
  EXPECT_EQ(error_of(raw_frame("just text", 0)), FrameError::header_not_mapping);
  EXPECT_EQ(error_of(raw_frame("{id: 1}", 0)), FrameError::missing_type);
  EXPECT_EQ(error_of(raw_frame("{type: [ping], id: 1}", 0)), FrameError::bad_type);
  EXPECT_EQ(error_of(raw_frame("{type: launch, id: 1}", 0)), FrameError::unknown_type);
  EXPECT_EQ(error_of(raw_frame("{type: ping}", 0)), FrameError::missing_id);
  EXPECT_EQ(error_of(raw_frame("{type: ping, id: -1}", 0)), FrameError::bad_id);
  EXPECT_EQ(error_of(raw_frame("{type: ping, id: \"1\"}", 0)), FrameError::bad_id);
  EXPECT_EQ(error_of(raw_frame("{type: ping, id: 18446744073709551616}", 0)), FrameError::bad_id);
  EXPECT_EQ(error_of(raw_frame("{type: ping, id: 1, id: 2}", 0)), FrameError::duplicate_key);
  EXPECT_EQ(error_of(raw_frame("{type: \"p\xffng\", id: 1}", 0)), FrameError::header_not_utf8);
  EXPECT_EQ(error_of(raw_frame(std::string(5000, '['), 0)), FrameError::header_not_yaml);
}

TEST(FrameDecoder, AcceptsBlockStyleYaml) {
  FrameDecoder d;
  d.feed(raw_frame("type: status\nid: 9\njob: 42\n", 0));
  auto f = d.next();
  ASSERT_TRUE(f);
  auto m = decode<Status>(*f);
  ASSERT_TRUE(m.ok());
  EXPECT_EQ(m->id, 9u);
  EXPECT_EQ(m->job, 42u);
}

TEST(FrameDecoder, StaysFailedAndKeepsEarlierFrames) {
  std::string s = encode_frame(encode(Ping{1})) + "garbage" + encode_frame(encode(Ping{2}));
  FrameDecoder d;
  d.feed(s);
  ASSERT_TRUE(d.failed());
  EXPECT_EQ(d.next()->id, 1u);
  EXPECT_FALSE(d.next());
  EXPECT_EQ(d.feed(encode_frame(encode(Ping{3}))), 0u);
  EXPECT_EQ(d.error()->code, FrameError::bad_magic);
}

TEST(FrameDecoder, TruncatedInput) {
  const std::string full = encode_frame(encode(examples::all()[9].message));  // submit, with payload
  for (std::size_t n = 1; n < full.size(); ++n) {
    FrameDecoder d;
    d.feed(std::string_view(full).substr(0, n));
    EXPECT_FALSE(d.failed());
    EXPECT_EQ(d.ready_frames(), 0u);
    d.finish();
    ASSERT_TRUE(d.failed());
    EXPECT_EQ(d.error()->code, FrameError::truncated);
  }
}

TEST(FrameDecoder, FuzzedMutationsNeverCrashOrThrow) {
  const std::string stream = all_examples_stream();
  DecoderLimits lim;
  lim.max_header_bytes = 4096;
  lim.max_payload_bytes = 1 << 16;
  std::mt19937_64 rng(12345);
  int failures = 0;
  for (int iter = 0; iter < 4000; ++iter) {
    std::string s = stream;
    int edits = 1 + static_cast<int>(rng() % 8);
    for (int e = 0; e < edits; ++e) {
      std::size_t pos = rng() % s.size();
      switch (rng() % 4) {
        case 0: s[pos] = static_cast<char>(rng()); break;                 // overwrite
        case 1: s[pos] = static_cast<char>(s[pos] ^ (1 << (rng() % 8))); break;  // bit flip
        case 2: s.erase(pos, 1 + rng() % 16); break;                      // delete
        default: s.insert(pos, 1 + rng() % 8, static_cast<char>(rng())); break;
      }
      if (s.empty()) s.assign(1, 'x');
    }
    FrameDecoder d(lim);
    std::string_view rest = s;
    std::size_t chunk = 1 + rng() % 64;
    EXPECT_NO_THROW({
      while (!rest.empty() && !d.failed()) {
        std::size_t n = d.feed(rest.substr(0, chunk));
        rest.remove_prefix(n);
        while (auto f = d.next()) {
          auto m = decode_message(*f);
          if (m) (void)encode_frame(encode(*m));
        }
      }
      d.finish();
    });
    failures += d.failed();
  }
  EXPECT_GT(failures, 0);
}
