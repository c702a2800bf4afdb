#include "protocol/frame.h"

#include <gtest/gtest.h>

#include "protocol/header_writer.h"

using namespace omega::protocol;

TEST(Frame, PreludeIsLittleEndianWithMagic) {
  std::string b = encode_frame(Frame{"{}", std::string(0x0102, 'x')});
  ASSERT_EQ(b.size(), 16u + 2 + 0x0102);
  EXPECT_EQ(b.substr(0, 4), "OMG1");
  const auto* p = reinterpret_cast<const std::uint8_t*>(b.data());
  EXPECT_EQ(p[4], 2);
  EXPECT_EQ(p[5], 0);
  EXPECT_EQ(p[8], 0x02);
  EXPECT_EQ(p[9], 0x01);
  for (int i = 10; i < 16; ++i) EXPECT_EQ(p[i], 0);
  EXPECT_EQ(get_u64le(p + 8), 0x0102u);
}

TEST(Frame, LittleEndianHelpersRoundTrip) {
  std::uint8_t buf[8];
  put_u64le(buf, 0x0123456789abcdefull);
  EXPECT_EQ(buf[0], 0xef);
  EXPECT_EQ(buf[7], 0x01);
  EXPECT_EQ(get_u64le(buf), 0x0123456789abcdefull);
  put_u32le(buf, 0xdeadbeef);
  EXPECT_EQ(buf[0], 0xef);
  EXPECT_EQ(get_u32le(buf), 0xdeadbeefu);
}

TEST(HeaderWriter, DoublesMatchPythonRepr) {
  // Expected strings are Python's repr() of the same values.
  EXPECT_EQ(format_double(0.0), "0.0");
  EXPECT_EQ(format_double(-0.0), "-0.0");
  EXPECT_EQ(format_double(1.0), "1.0");
  EXPECT_EQ(format_double(100.0), "100.0");
  EXPECT_EQ(format_double(4.25), "4.25");
  EXPECT_EQ(format_double(0.1), "0.1");
  EXPECT_EQ(format_double(0.031), "0.031");
  EXPECT_EQ(format_double(0.0001), "0.0001");
  EXPECT_EQ(format_double(0.00001), "1e-05");
  EXPECT_EQ(format_double(1.5e-7), "1.5e-07");
  EXPECT_EQ(format_double(1.5e6), "1500000.0");
  EXPECT_EQ(format_double(1e15), "1000000000000000.0");
  EXPECT_EQ(format_double(1e16), "1e+16");
  EXPECT_EQ(format_double(1.2345e16), "1.2345e+16");
  EXPECT_EQ(format_double(123456789.125), "123456789.125");
  EXPECT_EQ(format_double(1.7976931348623157e308), "1.7976931348623157e+308");
  EXPECT_EQ(format_double(5e-324), "5e-324");
  EXPECT_EQ(format_double(-2.5e-5), "-2.5e-05");
}

TEST(HeaderWriter, StringsEscapeLikeJson) {
  EXPECT_EQ(quote_string("a\"b\\c"), "\"a\\\"b\\\\c\"");
  EXPECT_EQ(quote_string("\n\t\r\b\f"), "\"\\n\\t\\r\\b\\f\"");
  EXPECT_EQ(quote_string(std::string("\x01\x1f", 2)), "\"\\u0001\\u001f\"");
  EXPECT_EQ(quote_string("é/\x7f"), "\"é/\x7f\"");
}

TEST(HeaderWriter, NestedStructures) {
  HeaderWriter w;
  w.begin_map().field("a", "x").key("l").begin_list().u64(1).i64(-2).begin_map().end_map().end_list();
  w.key("m").begin_map().field_f("f", 0.5).end_map().end_map();
  EXPECT_EQ(w.text(), R"({"a": "x", "l": [1, -2, {}], "m": {"f": 0.5}})");
}
