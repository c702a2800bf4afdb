#pragma once
// Parsing of frame headers: the checks every frame must pass (parse_header) and typed field
// access with range checks for message decoders (FieldReader).
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "protocol/errors.h"
#include "protocol/message_type.h"
#include "protocol/result.h"

namespace omega::protocol {

// A frame whose header has passed the framing checks: valid UTF-8, a YAML mapping without
// duplicate keys, a known `type` and a decimal `id`.
//
// YAML::Node assignment writes through to every node sharing the target, so these types rebind
// with reset() instead; assigning one frame to another never alters a third.
struct ParsedHeader {
  MessageType type{};
  std::uint64_t id = 0;
  YAML::Node header;

  ParsedHeader() = default;
  ParsedHeader(MessageType t, std::uint64_t i, const YAML::Node& h) : type(t), id(i), header(h) {}
  ParsedHeader(const ParsedHeader&) = default;
  ParsedHeader& operator=(const ParsedHeader& o) {
    type = o.type;
    id = o.id;
    header.reset(o.header);
    return *this;
  }
};

struct DecodedFrame {
  MessageType type{};
  std::uint64_t id = 0;
  YAML::Node header;
  std::string payload;

  DecodedFrame() = default;
  DecodedFrame(MessageType t, std::uint64_t i, const YAML::Node& h, std::string p)
      : type(t), id(i), header(h), payload(std::move(p)) {}
  DecodedFrame(const DecodedFrame&) = default;
  DecodedFrame(DecodedFrame&& o) noexcept
      : type(o.type), id(o.id), header(o.header), payload(std::move(o.payload)) {}
  DecodedFrame& operator=(const DecodedFrame& o) {
    if (this != &o) {
      type = o.type;
      id = o.id;
      header.reset(o.header);
      payload = o.payload;
    }
    return *this;
  }
  DecodedFrame& operator=(DecodedFrame&& o) noexcept {
    if (this != &o) {
      type = o.type;
      id = o.id;
      header.reset(o.header);
      payload = std::move(o.payload);
    }
    return *this;
  }
};

Result<ParsedHeader, FrameError> parse_header(std::string_view text);

bool is_valid_utf8(std::string_view s);
std::optional<std::uint64_t> parse_u64(std::string_view s);  // decimal digits only
std::optional<std::int64_t> parse_i64(std::string_view s);   // optional '-', then digits
std::optional<double> parse_f64(std::string_view s);         // finite decimal/exponent forms

// Reads fields of one mapping. The first problem is kept (with the dotted field path in its
// message) and later reads return defaults, so a decoder reads everything and checks once.
class FieldReader {
 public:
  explicit FieldReader(YAML::Node map, std::string path = {});

  bool ok() const { return !err_->has_value(); }
  Failure<DecodeError> failure() const { return **err_; }
  void fail(DecodeError code, const std::string& field, const std::string& what);

  bool has(std::string_view key) const;
  std::uint64_t u64(std::string_view key, std::uint64_t lo = 0,
                    std::uint64_t hi = std::numeric_limits<std::uint64_t>::max());
  std::optional<std::uint64_t> opt_u64(std::string_view key, std::uint64_t lo = 0,
                                       std::uint64_t hi = std::numeric_limits<std::uint64_t>::max());
  std::int64_t i64(std::string_view key, std::int64_t lo, std::int64_t hi);
  // lo_open: the lower bound itself is not allowed (e.g. time_s > 0).
  double f64(std::string_view key, double lo, double hi, bool lo_open = false);
  std::optional<double> opt_f64(std::string_view key, double lo, double hi, bool lo_open = false);
  std::string str(std::string_view key, std::size_t max_len = 4096);
  std::optional<std::string> opt_str(std::string_view key, std::size_t max_len = 4096);
  // A missing optional mapping reads as an empty one.
  FieldReader map(std::string_view key, bool required = true);
  std::vector<FieldReader> map_list(std::string_view key, std::size_t max_items);
  std::vector<std::string> str_list(std::string_view key, std::size_t max_items, std::size_t max_len);

  // Exactly `count` unsigned integers, each at most hi.
  std::vector<std::uint64_t> u64_list(std::string_view key, std::size_t count, std::uint64_t hi);

  std::string path_of(std::string_view key) const;

 private:
  FieldReader(YAML::Node map, std::string path,
              std::shared_ptr<std::optional<Failure<DecodeError>>> err);
  YAML::Node get(std::string_view key, bool required);
  std::optional<std::string> scalar_number(std::string_view key, const YAML::Node& n);
  std::optional<std::string> scalar_string(const std::string& path, const YAML::Node& n, std::size_t max_len);

  YAML::Node node_;
  std::string path_;
  std::shared_ptr<std::optional<Failure<DecodeError>>> err_;
};

}  // namespace omega::protocol
