// The atomic writer shared by every unit that writes files.
#include "test_support.hpp"

#include <hapsyn/output_files.hpp>

#include <boost/filesystem.hpp>

#include <fstream>
#include <sstream>

#include <unistd.h>

namespace fs = boost::filesystem;
using hapsyn::test::error_of;

namespace {
std::string read(const fs::path& p) {
  std::ifstream in(p.string(), std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}
}  // namespace

TEST(OutputFiles, WritesReplacesAndLeavesNoTemporaryFile) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-output-files-test-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path file = dir / "a.txt";
  hapsyn::write_file_atomically(file.string(), "first");
  EXPECT_EQ(read(file), "first");
  hapsyn::write_file_atomically(file.string(), {"head|", std::string("pay\0load", 8)});
  EXPECT_EQ(read(file), std::string("head|pay\0load", 13));
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    ++entries;
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << e.path();
  }
  EXPECT_EQ(entries, 1);
  fs::remove_all(dir);
}

TEST(OutputFiles, AMissingDirectoryIsAnOutputError) {
  const std::string what = error_of([] { hapsyn::write_file_atomically("/nonexistent-hapsyn-dir/x.json", "{}"); });
  EXPECT_EQ(what.rfind("output: cannot write /nonexistent-hapsyn-dir/.tmp-x.json-", 0), 0u) << what;
}

TEST(OutputFiles, ProvenanceIsFilledIn) {
  EXPECT_FALSE(std::string(hapsyn::version()).empty());
  EXPECT_TRUE(hapsyn::machine_info().contains("hardware_threads"));
  const std::string now = hapsyn::iso_time_now();
  ASSERT_EQ(now.size(), 20u) << now;
  EXPECT_EQ(now.back(), 'Z');
}
