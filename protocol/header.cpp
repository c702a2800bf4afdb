#include "protocol/header.h"

#include "protocol/header_writer.h"

#include <charconv>
#include <cmath>
#include <set>

namespace omega::protocol {

bool is_valid_utf8(std::string_view s) {
  std::size_t i = 0;
  while (i < s.size()) {
    auto c = static_cast<unsigned char>(s[i]);
    std::size_t n;
    std::uint32_t cp;
    if (c < 0x80) { ++i; continue; }
    if (c >= 0xC2 && c <= 0xDF) { n = 1; cp = c & 0x1F; }
    else if (c >= 0xE0 && c <= 0xEF) { n = 2; cp = c & 0x0F; }
    else if (c >= 0xF0 && c <= 0xF4) { n = 3; cp = c & 0x07; }
    else return false;
    if (i + n >= s.size()) return false;
    for (std::size_t k = 1; k <= n; ++k) {
      auto d = static_cast<unsigned char>(s[i + k]);
      if ((d & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (d & 0x3F);
    }
    // Overlong forms, surrogates and values past U+10FFFF.
    if ((n == 2 && cp < 0x800) || (n == 3 && (cp < 0x10000 || cp > 0x10FFFF)) ||
        (cp >= 0xD800 && cp <= 0xDFFF))
      return false;
    i += n + 1;
  }
  return true;
}

std::optional<std::uint64_t> parse_u64(std::string_view s) {
  if (s.empty() || s.size() > 20) return std::nullopt;
  for (char c : s)
    if (c < '0' || c > '9') return std::nullopt;
  std::uint64_t v = 0;
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<std::int64_t> parse_i64(std::string_view s) {
  std::string_view digits = (!s.empty() && s[0] == '-') ? s.substr(1) : s;
  if (digits.empty() || digits.size() > 19) return std::nullopt;
  for (char c : digits)
    if (c < '0' || c > '9') return std::nullopt;
  std::int64_t v = 0;
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

std::optional<double> parse_f64(std::string_view s) {
  // from_chars also accepts "inf"/"nan" spellings; require a digit so those never get through.
  if (s.empty() || s.size() > 64) return std::nullopt;
  bool digit = false;
  for (char c : s) {
    if (c >= '0' && c <= '9') digit = true;
    else if (c != '-' && c != '+' && c != '.' && c != 'e' && c != 'E') return std::nullopt;
  }
  if (!digit || s[0] == '+') return std::nullopt;
  double v = 0;
  auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  if (r.ec != std::errc() || r.ptr != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

namespace {
std::string format_range(double lo, double hi) {
  return format_double(lo) + ", " + format_double(hi) + "]";
}

// A quoted scalar ("7") is a string, never a number: YAML marks it with the non-specific tag "!".
bool is_plain_scalar(const YAML::Node& n) { return n.IsScalar() && n.Tag() != "!"; }
}  // namespace

Result<ParsedHeader, FrameError> parse_header(std::string_view text) {
  if (!is_valid_utf8(text)) return fail(FrameError::header_not_utf8, "header is not valid UTF-8");
  YAML::Node root;
  try {
    root.reset(YAML::Load(std::string(text)));
  } catch (const std::exception& e) {
    return fail(FrameError::header_not_yaml, std::string("header is not valid YAML: ") + e.what());
  }
  if (!root.IsMap()) return fail(FrameError::header_not_mapping, "header is not a YAML mapping");
  std::set<std::string> keys;
  for (const auto& kv : root) {
    if (!kv.first.IsScalar())
      return fail(FrameError::header_not_mapping, "header has a key that is not a scalar");
    if (!keys.insert(kv.first.Scalar()).second)
      return fail(FrameError::duplicate_key, "header repeats the key '" + kv.first.Scalar() + "'");
  }
  const YAML::Node& croot = root;
  YAML::Node type = croot["type"];
  if (!type.IsDefined()) return fail(FrameError::missing_type, "header has no 'type'");
  if (!type.IsScalar()) return fail(FrameError::bad_type, "header 'type' is not a string");
  auto t = message_type_from_string(type.Scalar());
  if (!t) {
    std::string shown = type.Scalar().substr(0, 64);
    return fail(FrameError::unknown_type, "unknown message type '" + shown + "'");
  }
  YAML::Node id = croot["id"];
  if (!id.IsDefined()) return fail(FrameError::missing_id, "header has no 'id'");
  std::optional<std::uint64_t> idv;
  if (is_plain_scalar(id)) idv = parse_u64(id.Scalar());
  if (!idv) return fail(FrameError::bad_id, "header 'id' is not an unsigned decimal integer");
  return ParsedHeader{*t, *idv, root};
}

FieldReader::FieldReader(YAML::Node map, std::string path)
    : FieldReader(std::move(map), std::move(path),
                  std::make_shared<std::optional<Failure<DecodeError>>>()) {}

FieldReader::FieldReader(YAML::Node map, std::string path,
                         std::shared_ptr<std::optional<Failure<DecodeError>>> err)
    : node_(std::move(map)), path_(std::move(path)), err_(std::move(err)) {}

std::string FieldReader::path_of(std::string_view key) const {
  return path_.empty() ? std::string(key) : path_ + "." + std::string(key);
}

void FieldReader::fail(DecodeError code, const std::string& field, const std::string& what) {
  if (err_->has_value()) return;
  *err_ = Failure<DecodeError>{code, field + ": " + what};
}

bool FieldReader::has(std::string_view key) const {
  if (!node_.IsMap()) return false;
  const YAML::Node& n = node_;
  return n[std::string(key)].IsDefined();
}

YAML::Node FieldReader::get(std::string_view key, bool required) {
  if (!ok() || !node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  const YAML::Node& n = node_;
  YAML::Node v = n[std::string(key)];
  if (!v.IsDefined()) {
    if (required) fail(DecodeError::missing_field, path_of(key), "missing");
    return YAML::Node(YAML::NodeType::Undefined);
  }
  return v;
}

std::optional<std::string> FieldReader::scalar_number(std::string_view key, const YAML::Node& n) {
  if (!is_plain_scalar(n)) {
    fail(DecodeError::wrong_type, path_of(key), "expected a number");
    return std::nullopt;
  }
  return n.Scalar();
}

std::optional<std::string> FieldReader::scalar_string(const std::string& path, const YAML::Node& n,
                                                      std::size_t max_len) {
  if (!n.IsScalar()) {
    fail(DecodeError::wrong_type, path, "expected a string");
    return std::nullopt;
  }
  if (n.Scalar().size() > max_len) {
    fail(DecodeError::out_of_range, path, "longer than " + std::to_string(max_len) + " bytes");
    return std::nullopt;
  }
  // The header text is UTF-8, but a double-quoted scalar's escapes (\N, \x85) unescape to bare
  // bytes that are not: such a string could not be sent on, since our own encoder writes it
  // raw and the peer would refuse the frame (found by fuzz_messages).
  if (!is_valid_utf8(n.Scalar())) {
    fail(DecodeError::invalid_value, path, "not valid UTF-8 once unescaped");
    return std::nullopt;
  }
  return n.Scalar();
}

std::optional<std::uint64_t> FieldReader::opt_u64(std::string_view key, std::uint64_t lo, std::uint64_t hi) {
  YAML::Node n = get(key, false);
  if (!n.IsDefined()) return std::nullopt;
  auto s = scalar_number(key, n);
  if (!s) return std::nullopt;
  auto v = parse_u64(*s);
  if (!v) {
    fail(DecodeError::wrong_type, path_of(key), "expected an unsigned decimal integer");
    return std::nullopt;
  }
  if (*v < lo || *v > hi) {
    fail(DecodeError::out_of_range, path_of(key),
         "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return std::nullopt;
  }
  return v;
}

std::uint64_t FieldReader::u64(std::string_view key, std::uint64_t lo, std::uint64_t hi) {
  if (ok() && !has(key)) fail(DecodeError::missing_field, path_of(key), "missing");
  return opt_u64(key, lo, hi).value_or(lo);
}

std::int64_t FieldReader::i64(std::string_view key, std::int64_t lo, std::int64_t hi) {
  YAML::Node n = get(key, true);
  if (!n.IsDefined()) return lo;
  auto s = scalar_number(key, n);
  if (!s) return lo;
  auto v = parse_i64(*s);
  if (!v) {
    fail(DecodeError::wrong_type, path_of(key), "expected a decimal integer");
    return lo;
  }
  if (*v < lo || *v > hi) {
    fail(DecodeError::out_of_range, path_of(key),
         "must be in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return lo;
  }
  return *v;
}

std::optional<double> FieldReader::opt_f64(std::string_view key, double lo, double hi, bool lo_open) {
  YAML::Node n = get(key, false);
  if (!n.IsDefined()) return std::nullopt;
  auto s = scalar_number(key, n);
  if (!s) return std::nullopt;
  auto v = parse_f64(*s);
  if (!v) {
    fail(DecodeError::wrong_type, path_of(key), "expected a finite decimal number");
    return std::nullopt;
  }
  if (*v < lo || *v > hi || (lo_open && *v == lo)) {
    fail(DecodeError::out_of_range, path_of(key),
         std::string("must be in ") + (lo_open ? "(" : "[") + format_range(lo, hi));
    return std::nullopt;
  }
  return v;
}

double FieldReader::f64(std::string_view key, double lo, double hi, bool lo_open) {
  if (ok() && !has(key)) fail(DecodeError::missing_field, path_of(key), "missing");
  return opt_f64(key, lo, hi, lo_open).value_or(lo);
}

std::optional<std::string> FieldReader::opt_str(std::string_view key, std::size_t max_len) {
  YAML::Node n = get(key, false);
  if (!n.IsDefined()) return std::nullopt;
  return scalar_string(path_of(key), n, max_len);
}

std::string FieldReader::str(std::string_view key, std::size_t max_len) {
  if (ok() && !has(key)) fail(DecodeError::missing_field, path_of(key), "missing");
  return opt_str(key, max_len).value_or(std::string());
}

FieldReader FieldReader::map(std::string_view key, bool required) {
  YAML::Node n = get(key, required);
  if (n.IsDefined() && !n.IsMap()) fail(DecodeError::wrong_type, path_of(key), "expected a mapping");
  return FieldReader(n.IsMap() ? n : YAML::Node(YAML::NodeType::Map), path_of(key), err_);
}

std::vector<FieldReader> FieldReader::map_list(std::string_view key, std::size_t max_items) {
  std::vector<FieldReader> out;
  YAML::Node n = get(key, true);
  if (!n.IsDefined()) return out;
  if (!n.IsSequence()) {
    fail(DecodeError::wrong_type, path_of(key), "expected a list");
    return out;
  }
  if (n.size() > max_items) {
    fail(DecodeError::out_of_range, path_of(key), "more than " + std::to_string(max_items) + " items");
    return out;
  }
  for (std::size_t i = 0; i < n.size(); ++i) {
    std::string p = path_of(key) + "[" + std::to_string(i) + "]";
    if (!n[i].IsMap()) {
      fail(DecodeError::wrong_type, p, "expected a mapping");
      return {};
    }
    out.push_back(FieldReader(n[i], p, err_));
  }
  return out;
}

std::vector<std::string> FieldReader::str_list(std::string_view key, std::size_t max_items,
                                               std::size_t max_len) {
  std::vector<std::string> out;
  YAML::Node n = get(key, true);
  if (!n.IsDefined()) return out;
  if (!n.IsSequence()) {
    fail(DecodeError::wrong_type, path_of(key), "expected a list");
    return out;
  }
  if (n.size() > max_items) {
    fail(DecodeError::out_of_range, path_of(key), "more than " + std::to_string(max_items) + " items");
    return out;
  }
  for (std::size_t i = 0; i < n.size(); ++i) {
    auto s = scalar_string(path_of(key) + "[" + std::to_string(i) + "]", n[i], max_len);
    if (!s) return {};
    out.push_back(*s);
  }
  return out;
}

std::vector<std::uint64_t> FieldReader::u64_list(std::string_view key, std::size_t count, std::uint64_t hi) {
  YAML::Node n = get(key, true);
  if (!n.IsDefined()) return {};
  if (!n.IsSequence() || n.size() != count) {
    fail(DecodeError::wrong_type, path_of(key), "expected a list of " + std::to_string(count) + " integers");
    return {};
  }
  std::vector<std::uint64_t> out;
  for (std::size_t i = 0; i < count; ++i) {
    std::string p = path_of(key) + "[" + std::to_string(i) + "]";
    std::optional<std::uint64_t> v;
    if (is_plain_scalar(n[i])) v = parse_u64(n[i].Scalar());
    if (!v) {
      fail(DecodeError::wrong_type, p, "expected an unsigned decimal integer");
      return {};
    }
    if (*v > hi) {
      fail(DecodeError::out_of_range, p, "must be at most " + std::to_string(hi));
      return {};
    }
    out.push_back(*v);
  }
  return out;
}

}  // namespace omega::protocol
