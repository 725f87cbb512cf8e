#include "cluster/archive.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace canalsim::cluster {
namespace {

struct Part {
  std::string name;
  double value = 0.0;
};
template <class Archive>
void fields(Archive& a, Part& p) {
  a(p.name, p.value);
}

struct Whole {
  int index = 0;
  bool flag = false;
  std::optional<Part> maybe;
  std::vector<Part> parts;
  std::vector<std::vector<int>> table;
  std::vector<bool> bits;
  double not_a_number = 0.0, tiny = 0.0;
};
template <class Archive>
void fields(Archive& a, Whole& w) {
  a(w.index, w.flag, w.maybe, w.parts, w.table, w.bits, w.not_a_number, w.tiny);
}

TEST(Archive, EveryFieldComesBackBitForBit) {
  Whole w;
  w.index = -7;
  w.flag = true;
  w.maybe = Part{"optional part", 0.1};
  w.parts = {{"", -0.0}, {std::string("nul\0inside", 10), std::numeric_limits<double>::infinity()}};
  w.table = {{1, 2, 3}, {}, {4}};
  w.bits = {true, false, true};
  w.not_a_number = std::numeric_limits<double>::quiet_NaN();
  w.tiny = std::nextafter(1.0, 2.0);  // the last bit: lost by a decimal text of 15 digits

  Whole back;
  unarchive(archive(w), back);
  EXPECT_EQ(back.index, -7);
  EXPECT_TRUE(back.flag);
  ASSERT_TRUE(back.maybe);
  EXPECT_EQ(back.maybe->name, "optional part");
  EXPECT_EQ(back.maybe->value, 0.1);
  ASSERT_EQ(back.parts.size(), 2u);
  EXPECT_TRUE(std::signbit(back.parts[0].value));
  EXPECT_EQ(back.parts[1].name, std::string("nul\0inside", 10));
  EXPECT_EQ(back.parts[1].value, std::numeric_limits<double>::infinity());
  EXPECT_EQ(back.table, w.table);
  EXPECT_EQ(back.bits, w.bits);
  EXPECT_EQ(std::bit_cast<std::uint64_t>(back.not_a_number), std::bit_cast<std::uint64_t>(w.not_a_number));
  EXPECT_EQ(back.tiny, w.tiny);
}

TEST(Archive, AnEmptyOptionalStaysEmpty) {
  Whole w;
  Whole back;
  back.maybe = Part{"stale", 1.0};
  unarchive(archive(w), back);
  EXPECT_FALSE(back.maybe);
}

TEST(Archive, TruncatedOrLongerBytesAreRefused) {
  Whole w;
  w.parts = {{"a name", 1.0}};
  const std::string bytes = archive(w);
  Whole back;
  for (std::size_t keep : {std::size_t{0}, std::size_t{3}, bytes.size() / 2, bytes.size() - 1}) {
    EXPECT_THROW(unarchive(bytes.substr(0, keep), back), std::runtime_error) << keep << " bytes";
  }
  EXPECT_THROW(unarchive(bytes + "x", back), std::runtime_error);
}

TEST(Archive, ASizePastTheEndIsRefusedBeforeAllocating) {
  std::string bytes(sizeof(std::uint64_t), '\xff');  // a string "of 2^64 - 1 characters"
  std::string text;
  EXPECT_THROW(unarchive(bytes, text), std::runtime_error);
}

}  // namespace
}  // namespace canalsim::cluster
