// The acceptance criteria on the shipped five-bar problems (slow: about a minute):
// NBI against the exhaustive 5 mm grid front, the weighted sum's clumping and time, and the
// sequential design's domination (Unal 2008, Figures 3, 4 and 7).
#include "test_support.hpp"

#include <boost/filesystem.hpp>

using hapsyn::Json;
namespace fs = boost::filesystem;

namespace {
Json run_problem(const std::string& name, const fs::path& out, const std::string& reference) {
  Json doc = hapsyn::read_problem_file(std::string(HAPSYN_SOURCE_DIR) + "/problems/" + name + ".json");
  if (!reference.empty()) doc["indicators"]["reference_front"] = reference;
  hapsyn::Study study = hapsyn::load_study(doc, hapsyn::test::registry());
  hapsyn::RunOptions options;
  options.output_directory = (out / name).string();
  options.threads = 2;
  options.quiet = true;
  return hapsyn::run_study(study, options);
}
}  // namespace

TEST(NbiPaper, FiveBarFrontMatchesExhaustiveSearchAndBeatsWeightedSums) {
  const fs::path out = fs::temp_directory_path() / fs::unique_path("hapsyn-nbi-paper-%%%%%%");
  const Json reference = run_problem("fivebar-pareto-reference", out, "");
  const std::string reference_file = (out / "fivebar-pareto-reference" / "result.json").string();
  const Json nbi = run_problem("fivebar-pareto-nbi", out, reference_file);
  const Json ws = run_problem("fivebar-pareto-weighted-sum", out, reference_file);
  const Json seq = run_problem("fivebar-pareto-sequential", out, reference_file);

  const Json& in = nbi["indicators"];
  EXPECT_EQ(in["points"], 10);
  EXPECT_LE(in["max_domination_gap"]["gii"].get<double>(), 0.002);
  EXPECT_LE(in["max_domination_gap"]["gdi"].get<double>(), 0.002);
  EXPECT_LT(in["generational_distance"].get<double>(), 0.005);
  // Span: from the GII optimum to the GDI optimum of the exhaustive front (or beyond).
  const Json& ref_extent = reference["indicators"]["extent"];
  EXPECT_GE(in["extent"]["gii"][1].get<double>(), ref_extent["gii"][1].get<double>() - 0.002);
  EXPECT_GE(in["extent"]["gdi"][1].get<double>(), ref_extent["gdi"][1].get<double>() - 0.002);
  // More uniform than the weighted sum, which clumps; at least 5 times faster.
  EXPECT_LT(in["spacing_relative"].get<double>(), ws["indicators"]["spacing_relative"].get<double>());
  EXPECT_LT(ws["front"].size(), 10u);
  EXPECT_GT(ws["wall_time_s"].get<double>(), 5 * nbi["wall_time_s"].get<double>());
  // The sequential design is dominated (Figure 7).
  EXPECT_TRUE(seq["indicators"]["best_dominated"].get<bool>());
  EXPECT_GT(seq["indicators"]["best_domination_gap"]["gii"].get<double>(), 0.05);
  fs::remove_all(out);
}
