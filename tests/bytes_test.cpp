// The binary records ranks pass each other (hapsyn/bytes.hpp): what a ByteWriter writes, a
// ByteReader reads back bit for bit, however the writer's buffer grew.
#include <hapsyn/bytes.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

TEST(Bytes, MixedValuesRoundTripBitForBit) {
  hapsyn::ByteWriter out;
  const std::vector<double> values{1.0, -0.0, std::numeric_limits<double>::denorm_min(), 0.1 + 0.2};
  out.put(42LL).put(std::numeric_limits<double>::quiet_NaN()).put_vector(values).put_string("line 17").put(7);
  const std::string bytes = out.take();
  EXPECT_EQ(bytes.size(), sizeof(long long) + sizeof(double) + 8 + 4 * sizeof(double) + 8 + 7 + sizeof(int));
  hapsyn::ByteReader in(bytes);
  EXPECT_EQ(in.get<long long>(), 42);
  EXPECT_TRUE(std::isnan(in.get<double>()));
  const std::vector<double> back = in.get_vector();
  ASSERT_EQ(back.size(), values.size());
  for (std::size_t k = 0; k < values.size(); ++k) {
    EXPECT_EQ(std::signbit(back[k]), std::signbit(values[k]));
    EXPECT_EQ(back[k], values[k]);
  }
  EXPECT_EQ(in.get_string(), "line 17");
  EXPECT_EQ(in.get<int>(), 7);
  EXPECT_TRUE(in.at_end());
}

TEST(Bytes, GrowingBufferKeepsEveryValueAndBytesShowsOnlyWhatWasWritten) {
  hapsyn::ByteWriter out;
  for (long long k = 0; k < 10000; ++k) {
    out.put(k);
    if (k == 3) {
      EXPECT_EQ(out.bytes().size(), 4 * sizeof(long long));  // mid-way, then more puts
    }
  }
  EXPECT_EQ(out.bytes().size(), 10000 * sizeof(long long));
  const std::string bytes = out.take();
  hapsyn::ByteReader in(bytes);
  for (long long k = 0; k < 10000; ++k) ASSERT_EQ(in.get<long long>(), k);
  EXPECT_TRUE(in.at_end());
}

TEST(Bytes, TakeLeavesAnEmptyWriterThatWritesAfresh) {
  hapsyn::ByteWriter out;
  out.put(1.5);
  EXPECT_EQ(out.take().size(), sizeof(double));
  EXPECT_TRUE(out.bytes().empty());
  out.put(2);
  const std::string bytes = out.take();
  hapsyn::ByteReader in(bytes);
  EXPECT_EQ(in.get<int>(), 2);
  EXPECT_TRUE(in.at_end());
}

TEST(Bytes, ReadingPastTheEndIsAnErrorNamingATruncatedMessage) {
  hapsyn::ByteWriter out;
  out.put(1);
  const std::string bytes = out.take();
  hapsyn::ByteReader in(bytes);
  EXPECT_EQ(in.get<int>(), 1);
  try {
    (void)in.get<double>();
    FAIL() << "no error";
  } catch (const hapsyn::Error& e) {
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cluster"), std::string::npos) << e.what();
  }
}

}  // namespace
