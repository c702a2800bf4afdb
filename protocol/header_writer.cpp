#include "protocol/header_writer.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <system_error>

namespace omega::protocol {

std::string format_double(double v) {
  // Non-finite values have no JSON spelling; decoders reject them, so encoders never see them
  // unless a caller bypassed validation. Write 0 rather than emit an unreadable header.
  if (!std::isfinite(v)) v = 0.0;
  char buf[64];
  // Shortest round-trip digits in scientific form, e.g. "1.5e-05", "-1e+16".
  auto r = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific);
  std::string_view sci(buf, static_cast<std::size_t>(r.ptr - buf));
  bool neg = !sci.empty() && sci[0] == '-';
  if (neg) sci.remove_prefix(1);
  auto epos = sci.find('e');
  std::string mant(sci.substr(0, epos));
  int exp10 = std::stoi(std::string(sci.substr(epos + 1)));
  std::string digits;
  for (char c : mant)
    if (c != '.') digits += c;
  while (digits.size() > 1 && digits.back() == '0') digits.pop_back();

  std::string out = neg ? "-" : "";
  if (exp10 >= -4 && exp10 < 16) {
    if (exp10 < 0) {
      out += "0.";
      out.append(static_cast<std::size_t>(-exp10 - 1), '0');
      out += digits;
    } else {
      auto int_len = static_cast<std::size_t>(exp10) + 1;
      if (digits.size() <= int_len) {
        out += digits;
        out.append(int_len - digits.size(), '0');
        out += ".0";
      } else {
        out += digits.substr(0, int_len);
        out += '.';
        out += digits.substr(int_len);
      }
    }
  } else {
    out += digits[0];
    if (digits.size() > 1) {
      out += '.';
      out += digits.substr(1);
    }
    char e[16];
    std::snprintf(e, sizeof e, "e%c%02d", exp10 < 0 ? '-' : '+', exp10 < 0 ? -exp10 : exp10);
    out += e;
  }
  return out;
}

std::string quote_string(std::string_view s) {
  std::string out;
  out.reserve(s.size() + 2);
  out += '"';
  for (char ch : s) {
    auto c = static_cast<unsigned char>(ch);
    switch (c) {
      case '"': out += "\\\""; break;
      case '\\': out += "\\\\"; break;
      case '\b': out += "\\b"; break;
      case '\t': out += "\\t"; break;
      case '\n': out += "\\n"; break;
      case '\f': out += "\\f"; break;
      case '\r': out += "\\r"; break;
      default:
        if (c < 0x20) {
          char e[8];
          std::snprintf(e, sizeof e, "\\u%04x", c);
          out += e;
        } else {
          out += ch;
        }
    }
  }
  out += '"';
  return out;
}

void HeaderWriter::before_value() {
  if (stack_.empty()) {
    if (!out_.empty()) throw std::logic_error("HeaderWriter: a second top-level value");
    return;
  }
  Level& l = stack_.back();
  if (l.is_map) {
    if (!l.after_key) throw std::logic_error("HeaderWriter: value without key");
    l.after_key = false;
  } else {
    if (!l.empty) out_ += ", ";
    l.empty = false;
  }
}

HeaderWriter& HeaderWriter::begin_map() {
  before_value();
  out_ += '{';
  stack_.push_back(Level{true});
  return *this;
}

HeaderWriter& HeaderWriter::end_map() {
  if (stack_.empty() || !stack_.back().is_map || stack_.back().after_key)
    throw std::logic_error("HeaderWriter: unbalanced end_map");
  stack_.pop_back();
  out_ += '}';
  return *this;
}

HeaderWriter& HeaderWriter::begin_list() {
  before_value();
  out_ += '[';
  stack_.push_back(Level{false});
  return *this;
}

HeaderWriter& HeaderWriter::end_list() {
  if (stack_.empty() || stack_.back().is_map) throw std::logic_error("HeaderWriter: unbalanced end_list");
  stack_.pop_back();
  out_ += ']';
  return *this;
}

HeaderWriter& HeaderWriter::key(std::string_view k) {
  if (stack_.empty() || !stack_.back().is_map || stack_.back().after_key)
    throw std::logic_error("HeaderWriter: key outside a map");
  Level& l = stack_.back();
  if (!l.empty) out_ += ", ";
  l.empty = false;
  l.after_key = true;
  out_ += quote_string(k);
  out_ += ": ";
  return *this;
}

HeaderWriter& HeaderWriter::str(std::string_view v) {
  before_value();
  out_ += quote_string(v);
  return *this;
}

HeaderWriter& HeaderWriter::u64(std::uint64_t v) {
  before_value();
  out_ += std::to_string(v);
  return *this;
}

HeaderWriter& HeaderWriter::i64(std::int64_t v) {
  before_value();
  out_ += std::to_string(v);
  return *this;
}

HeaderWriter& HeaderWriter::f64(double v) {
  before_value();
  out_ += format_double(v);
  return *this;
}

}  // namespace omega::protocol
