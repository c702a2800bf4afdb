#pragma once
// Writes headers in the canonical form of docs/protocol.md ("Canonical header form"): one line
// of JSON with ", " and ": " separators. JSON is a subset of YAML 1.2, so any YAML reader accepts
// it, and a client in another language can read our headers with a plain JSON parser. Being
// canonical (fixed key order, fixed number format) makes encode(decode(bytes)) == bytes.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace omega::protocol {

// The shortest decimal that reads back to v, laid out like Python's repr(float): fixed notation
// with at least one fractional digit when 1e-4 <= |v| < 1e16, otherwise d.ddde[+-]XX.
std::string format_double(double v);

// A JSON string literal: escapes only '"', '\\' and code points below 0x20 (\b \t \n \f \r, the
// rest as \u00xx); everything else is copied as UTF-8.
std::string quote_string(std::string_view s);

class HeaderWriter {
 public:
  HeaderWriter& begin_map();
  HeaderWriter& end_map();
  HeaderWriter& begin_list();
  HeaderWriter& end_list();
  HeaderWriter& key(std::string_view k);
  HeaderWriter& str(std::string_view v);
  HeaderWriter& u64(std::uint64_t v);
  HeaderWriter& i64(std::int64_t v);
  HeaderWriter& f64(double v);

  // Convenience: key followed by value.
  HeaderWriter& field(std::string_view k, std::string_view v) { return key(k).str(v); }
  HeaderWriter& field(std::string_view k, const char* v) { return key(k).str(v); }
  HeaderWriter& field(std::string_view k, const std::string& v) { return key(k).str(v); }
  HeaderWriter& field_u(std::string_view k, std::uint64_t v) { return key(k).u64(v); }
  HeaderWriter& field_i(std::string_view k, std::int64_t v) { return key(k).i64(v); }
  HeaderWriter& field_f(std::string_view k, double v) { return key(k).f64(v); }

  const std::string& text() const { return out_; }
  std::string take() { return std::move(out_); }

 private:
  void before_value();
  struct Level {
    bool is_map;
    bool empty = true;
    bool after_key = false;
  };
  std::string out_;
  std::vector<Level> stack_;
};

}  // namespace omega::protocol
