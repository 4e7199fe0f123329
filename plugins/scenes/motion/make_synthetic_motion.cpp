// hapsyn-make-synthetic-motion: writes the synthetic arm motion data set (share/motion/synthetic/)
// as <out>/csv/<subject>/<activity>.csv and <out>/bvh/<subject>/<activity>.bvh, and prints what
// it made (subject arm scales, samples, durations, bytes) for the data set's README.
#include "synthetic_motion.hpp"

#include <hapsyn/error.hpp>

#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

namespace {

namespace fs = std::filesystem;
using namespace hapsyn::plugins;

// Writes text to path (creating its folder); returns the bytes written.
std::size_t write_file(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw hapsyn::Error("motion", path.string() + ": cannot write");
  return text.size();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Writes the SYNTHETIC human arm motion data set (Fennel 2022 arm model, not recorded motion)."};
  std::string out_dir, arm_file;
  motion::SyntheticOptions options;
  app.add_option("--out", out_dir, "Output folder (gets csv/ and bvh/)")->required();
  app.add_option("--seed", options.seed, "Random seed")->capture_default_str();
  app.add_option("--arm", arm_file, "Arm file (default: share/human_arm/fennel2022_right_arm.json)");
  CLI11_PARSE(app, argc, argv);
  try {
    const HumanArmData arm = load_human_arm(resolve_arm_file(arm_file));
    const auto trajectories = motion::make_synthetic_motion(arm, options);
    std::size_t total_bytes = 0, total_samples = 0;
    std::printf("subject scale     activity   samples duration_s csv_bytes bvh_bytes\n");
    for (const auto& t : trajectories) {
      const fs::path base(out_dir);
      const std::size_t csv = write_file(base / "csv" / t.subject / (t.activity + ".csv"), motion::motion_csv(t));
      const std::size_t bvh = write_file(base / "bvh" / t.subject / (t.activity + ".bvh"),
                                         motion::motion_bvh(t, motion::scaled_arm(arm, t.arm_scale)));
      total_bytes += csv + bvh;
      total_samples += static_cast<std::size_t>(t.time.size());
      std::printf("%-7s %.6f %-10s %7ld %10.4f %9zu %9zu%s\n", t.subject.c_str(), t.arm_scale, t.activity.c_str(),
                  static_cast<long>(t.time.size()), t.path.duration(), csv, bvh, t.jittered ? " jittered" : "");
    }
    std::printf("total: %zu files, %zu samples, %zu bytes (seed %llu)\n", 2 * trajectories.size(), total_samples,
                total_bytes, static_cast<unsigned long long>(options.seed));
  } catch (const std::exception& e) {
    std::cerr << "hapsyn-make-synthetic-motion: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
