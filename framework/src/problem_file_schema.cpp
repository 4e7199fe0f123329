// The problem file's schema from its declarations (problem_file_schema.hpp): the keys, defaults,
// rules and descriptions of every framework key of a problem file.
#include "problem_file_schema.hpp"

#include <hapsyn/internal/reference.hpp>
#include <hapsyn/schema.hpp>

namespace hapsyn {

void ObjectiveDeclaration::declare(OptionDeclarations<ObjectiveDeclaration>& d) {
  d.add(&ObjectiveDeclaration::metric, "metric", {}, "Metric plugin name").required();
  d.add(&ObjectiveDeclaration::name, "name", "Label (default: the metric name)");
  d.add(&ObjectiveDeclaration::sense, "sense", "maximize", "Whether larger or smaller values of the metric are better")
      .one_of({"maximize", "minimize"});
  d.add(&ObjectiveDeclaration::weight, "weight", 1.0, "Weight in a weighted-sum study (>= 0; use sense to minimize)")
      .minimum(0);
  d.add(&ObjectiveDeclaration::options, "options", "Options of the metric plugin");
}

void OutputDeclaration::declare(OptionDeclarations<OutputDeclaration>& d) {
  d.add(&OutputDeclaration::directory, "directory", "Output directory (default results/<name>)");
  d.add(&OutputDeclaration::samples_csv, "samples_csv", true, "Write samples.csv for the best design");
  d.add(&OutputDeclaration::maps, "maps", true,
        "Write maps.csv: every objective per workspace position for the best design");
  d.add(&OutputDeclaration::plots, "plots", false,
        "Draw figures with gnuplot, each as PNG and SVG: the position maps (map_<objective>: slices by height for "
        "3-D scenes), a Pareto front (front), the GA's and NSGA-II's convergence (convergence) and, for scenes of "
        "recorded motion, one trajectory (timeline)");
  d.add(&OutputDeclaration::groups, "groups", true,
        "For scenes that group their samples (subject, activity, trajectory): every objective per group with the "
        "mean and standard deviation across groups, in result.json and groups.csv");
  d.add(&OutputDeclaration::timeline, "timeline",
        "With plots: the trajectory drawn in timeline.png (every objective on each sample along time); default the "
        "scene's first trajectory");
}

void IndicatorsDeclaration::declare(OptionDeclarations<IndicatorsDeclaration>& d) {
  d.add(&IndicatorsDeclaration::reference_front, "reference_front",
        "result.json of a study whose front is the reference (IGD, GD, domination gaps)");
  d.add(&IndicatorsDeclaration::reference_point, "reference_point",
        "Hypervolume reference point, one value per objective (natural units), worse than every front point");
}

void ProblemFileDeclaration::declare(OptionDeclarations<ProblemFileDeclaration>& d) {
  using P = ProblemFileDeclaration;
  d.add(&P::name, "name", "study", "Study name (used for the default output directory)");
  d.add(&P::description, "description", "", "Free text");
  // Required, in this order: a problem file missing several is told about the first.
  d.add(&P::mechanism, "mechanism", "What is designed: a mechanism plugin and its options").required();
  d.add(&P::scene, "scene", "The task-space samples the mechanism must serve: a scene plugin and its options")
      .required();
  d.add(&P::objectives, "objectives",
        "What is optimized: one entry per metric (several for a Pareto study or a weighted sum)")
      .required()
      .min_size(1);
  d.add(&P::solver, "solver", "How the design space is searched: a solver plugin and its options").required();
  d.add(&P::output, "output", "What the run writes besides result.json");
  // Optional without a default: a problem without indicators resolves without the section.
  d.add(&P::indicators, "indicators", "Front-quality indicators written into result.json");
  d.add(&P::design, "design",
        "The mechanism's design variables by name (hapsyn describe MECHANISM lists them), each an object with "
        "\"lower\" and \"upper\" (bounds of the search, within the variable's hard limits), \"step\" (grid spacing "
        "for grid solvers) or \"value\" (fixes it); a vector variable takes lists. A variable not named keeps its "
        "declared default bounds. Checked against the mechanism's declarations, not by this schema");
  d.add(&P::seed, "seed", "Random seed, an unsigned 64-bit integer (default: drawn and recorded)");
  d.add(&P::threads, "threads", "Worker threads (0 = all cores)").range(0, 1024);
}

// Made once and checked like a plugin's schema: every load validates against the same document.
const Json& problem_file_schema() {
  static const Json schema = [] {
    Json s = options_schema<ProblemFileDeclaration>();
    check_schema(s, "the problem file");
    return s;
  }();
  return schema;
}

}  // namespace hapsyn
