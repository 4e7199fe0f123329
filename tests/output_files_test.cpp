// The atomic writer shared by every unit that writes files.
#include "test_support.hpp"

#include <hapsyn/output_files.hpp>

#include <boost/filesystem.hpp>

#include <cstdint>
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

// ---- run.log, the directory lock, free space ----

namespace {
fs::path fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("hapsyn-output-files-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}
}  // namespace

TEST(OutputFiles, LogFileWritesEachLineAndAppendsOnRequest) {
  const fs::path dir = fresh("log");
  const std::string log = (dir / "run.log").string();
  {
    hapsyn::LogFile file(log, false);
    file.stream() << "first " << 1 << "\n";
    EXPECT_EQ(read(log), "first 1\n") << "a finished line is on disk at once";
  }
  {
    hapsyn::LogFile file(log, true);
    file.stream() << "second\n";
  }
  EXPECT_EQ(read(log), "first 1\nsecond\n");
  {
    hapsyn::LogFile file(log, false);
    file.stream() << "fresh\n";
  }
  EXPECT_EQ(read(log), "fresh\n");
  {
    hapsyn::LogFile file(log, true);
    file.truncate();
    file.stream() << "after truncate\n";
  }
  EXPECT_EQ(read(log), "after truncate\n");
  fs::remove_all(dir);
}

TEST(OutputFiles, LogFileRefusesASymbolicLinkAndLeavesItsTarget) {
  const fs::path dir = fresh("log-link");
  std::ofstream((dir / "precious").string()) << "keep";
  fs::create_symlink(dir / "precious", dir / "run.log");
  const std::string what = error_of([&] { hapsyn::LogFile file((dir / "run.log").string(), false); });
  EXPECT_EQ(what, "output: " + (dir / "run.log").string() +
                      " is a symbolic link; a run log is never written through one (remove it)");
  EXPECT_EQ(read(dir / "precious"), "keep");
  fs::remove_all(dir);
}

TEST(OutputFiles, ASecondLockOnADirectoryFailsAtOnceNamingTheHolder) {
  const fs::path dir = fresh("lock");
  {
    const hapsyn::DirectoryLock first(dir.string());
    const std::string what = error_of([&] { hapsyn::DirectoryLock second(dir.string()); });
    EXPECT_EQ(what, "output: " + dir.string() + " is in use by another hapsyn run (pid " + std::to_string(::getpid()) +
                        "); wait for it to end, or choose another --out");
  }
  EXPECT_EQ(error_of([&] { hapsyn::DirectoryLock again(dir.string()); }), "(no error)") << "released with its owner";
  fs::remove_all(dir);
}

TEST(OutputFiles, TooLittleFreeSpaceIsRefusedWithTheSizes) {
  const fs::path dir = fresh("space");
  EXPECT_GT(hapsyn::free_bytes(dir.string()), 0u);
  const std::string what =
      error_of([&] { hapsyn::check_free_space(dir.string(), std::uint64_t{1} << 62, "samples.csv (9 rows x 9 columns)"); });
  EXPECT_EQ(what.rfind("output: " + dir.string() + ": only ", 0), 0u) << what;
  EXPECT_NE(what.find(" MiB free on its file system; this run's outputs (samples.csv (9 rows x 9 columns)) need about "
                      "4398046511104.0 MiB; free some space or choose another --out"),
            std::string::npos)
      << what;
  EXPECT_EQ(error_of([&] { hapsyn::check_free_space(dir.string(), 1000, "result.json"); }), "(no error)");
  const std::string missing = error_of([] { hapsyn::free_bytes("/nonexistent-hapsyn-dir"); });
  EXPECT_EQ(missing, "output: cannot query the free space of /nonexistent-hapsyn-dir: No such file or directory");
  fs::remove_all(dir);
}
