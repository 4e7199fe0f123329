#pragma once
/// \file
/// The solve's per-sample records, kept for the outputs phase (docs/design.md section 11.6).
///
/// A study whose design is fixed (Problem::dimension() == 0, the `evaluate` solver's studies) has
/// one design, so the solve evaluates exactly the design whose samples.csv, maps.csv and
/// groups.csv the outputs phase writes. While a SolveRecording lives, the framework passes the
/// samples of a Problem::evaluate_parallel of that design through the recording callback: the
/// outputs phase then takes those records instead of evaluating every sample again. No plugin
/// sees it: the hook is in the framework's evaluator, not in the Solver API. Studies on the
/// block path (Problem::block_path()) are not recorded: the callback would take them off it and
/// change the solve's sums in the last bit; their outputs phase takes record_samples' one pass.
#include <hapsyn/internal/maps.hpp>

#include <atomic>
#include <vector>

namespace hapsyn {

/// Records one design's samples during the solve. Register it before the solve; afterwards
/// complete() says whether some evaluation covered every sample.
class SolveRecording {
 public:
  /// Records evaluations of `full_design` (all components) of a problem with `problem`'s
  /// mechanism, scene and metrics (the same objects: with_objectives() problems match too).
  SolveRecording(const Problem& problem, const Eigen::VectorXd& full_design);
  ~SolveRecording();
  SolveRecording(const SolveRecording&) = delete;
  SolveRecording& operator=(const SolveRecording&) = delete;

  /// True when an evaluate_parallel of the design over every sample ended feasible: every
  /// sample then has its status and local values, exactly as record_samples gives them (the
  /// same per-sample path; a feasible evaluation never stopped at a sample).
  bool complete() const { return complete_; }
  /// The records; valid when complete().
  const SampleRecords& records() const { return records_; }
  const Eigen::VectorXd& design() const { return design_; }

  /// For Evaluator::evaluate_parallel over every sample, off the block path: a live recording of
  /// this problem (its mechanism, scene, metrics) and design, which the caller then owns until
  /// finish(); null when there is none or another evaluation holds it. One atomic load when no
  /// recording lives (the usual case).
  static SolveRecording* claim(const Mechanism* mechanism, const SampleSet* samples,
                               const std::vector<MetricEntry>& metrics, const Eigen::VectorXd& full_design);
  const SampleCallback& callback() const { return callback_; }
  /// Ends a claim: `feasible` when the evaluation reached every sample; otherwise the records are
  /// incomplete and another evaluation of the design may claim the recording.
  void finish(bool feasible);
  /// True when some recording lives (the evaluator's cheap first test).
  static bool any() { return live_.load(std::memory_order_relaxed) > 0; }

 private:
  const Mechanism* mechanism_;
  const SampleSet* samples_;
  std::vector<const Metric*> metrics_;
  Eigen::VectorXd design_;
  SampleRecords records_;
  SampleCallback callback_;
  bool claimed_ = false, complete_ = false;  // guarded by the registry's mutex
  static std::atomic<int> live_;
};

/// Empty records of every sample of `problem` (no status, no locals): what record_samples and a
/// SolveRecording fill.
SampleRecords blank_records(const Problem& problem);
/// The callback writing a sample's status and locals into `records`: each call writes only its
/// own sample's entries, so threads evaluating different samples never share a write.
SampleCallback record_into(SampleRecords& records);

}  // namespace hapsyn
