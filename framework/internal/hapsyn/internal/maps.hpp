#pragma once
/// \file
/// Per-sample records and per-position maps of one design: what a user plots as the
/// distribution of a metric over the workspace (Fennel 2022, Figure 5; Unal 2008, Figure 2).
#include <hapsyn/problem.hpp>

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

namespace hapsyn {

/// Every sample of one design, each evaluated on its own so that every one is classified, also
/// past the first unreachable one (where a worst-case evaluation stops).
struct SampleRecords {
  std::vector<std::string> status;  ///< per sample: "reachable", "unreachable", ...
  std::vector<char> has_locals;     ///< per sample: 1 when the metrics' local values were computed
  Eigen::MatrixXd locals;           ///< samples x (all metrics' locals, in Metric::locals() order)
};

/// The status of a sample an evaluation did not reach with its callback (the sample it stopped at,
/// or every sample of a design that violates a constraint).
using UnreachedSample = std::function<void(int sample, const std::string& status)>;

/// Evaluates `full_design` (all components) once on every sample, as record_samples below does:
/// `record` gets every sample the evaluation reaches, `unreached` the others with their status.
/// Both are called on the pieces' threads, each time for one sample (write only its entries).
/// \throws Error as Problem::evaluate: the error of the lowest-numbered sample raising one.
void evaluate_each_sample(const Problem& problem, const Eigen::VectorXd& full_design, int threads,
                          const SampleCallback& record, const UnreachedSample& unreached);

/// Evaluates `full_design` (all components) on every sample: the records are exactly those of
/// evaluating each sample on its own (its status; its local values where computed), also past a
/// sample a worst-case evaluation stops at. One pass (docs/design.md section 11.6): contiguous
/// pieces of the samples on `threads` threads, the model built once per piece, each sample solved
/// once; after a sample that stops a piece's evaluation the piece resumes at the next one.
/// The callback writes only its own sample's entries, so the pieces never share a write.
/// \throws Error as Problem::evaluate: the error of the lowest-numbered sample raising one.
SampleRecords record_samples(const Problem& problem, const Eigen::VectorXd& full_design, int threads = 1);

/// The names of the local-value columns of samples.csv, one per local of every metric in order:
/// "<metric>.<local>", and "<metric>.<local>[k]" for the k-th (from 0) of names that would repeat
/// (a metric used by several objectives), so every name is unique.
std::vector<std::string> local_columns(const Problem& problem);

/// samples.csv: sample, the scene coordinates, `weight` when the scene has SampleSet::weights,
/// status, then the local_columns (local values as computed, before weighting).
std::string samples_csv(const Problem& problem, const SampleRecords& records);

/// Every objective's value per group of samples: group[i] in [0, G) is sample i's group,
/// samples_per_group[g] the count of group g (G entries). Each group's locals are reduced as the
/// evaluator reduces the whole scene and combined by Metric::combine; with SampleSet::weights,
/// its sum-reduced locals are scaled by w_i n_g / W_g (the group's weighted mean; a group whose
/// weights are equal or all 0 is reduced unweighted). \returns G x objectives; NaN where a
/// metric has no locals for a sample of the group (a worst-case metric met an unreachable one).
Eigen::MatrixXd grouped_objective_values(const Problem& problem, const SampleRecords& records,
                                         const std::vector<int>& group, const std::vector<int>& samples_per_group);

/// Every objective's value per workspace position: the samples at one position (one lattice
/// point of a scene that declares a SampleLattice, such as human_arm, else equal x, y, z
/// coordinates) are reduced as the metric reduces the whole scene and combined by
/// Metric::combine. For the coverage metric this is the per-position J_x (reachable share of
/// the human poses there), J_v, J_a, J_f. With SampleSet::weights, the sum-reduced locals of
/// the samples at a position are scaled by w_i n / W (n samples there, W their weight), so an
/// averaging objective is the position's weighted mean; a position whose weights are equal or
/// all 0 is reduced unweighted.
struct PositionMaps {
  std::vector<std::string> objectives;  ///< column names (the objectives' names)
  std::vector<Eigen::Vector3d> position;  ///< per position: x, y, z scene coordinates (0 when absent)
  std::vector<int> samples;               ///< per position: samples there
  std::vector<int> lattice_index;         ///< per position: SampleLattice index (lattice scenes), else -1
  Eigen::MatrixXd values;                 ///< positions x objectives; NaN = undefined (a worst-case
                                          ///< metric met an unreachable sample there)
  int lattice_per_axis = 0;               ///< SampleLattice::per_axis; 0 without a lattice
  double lattice_step = 0.0;              ///< SampleLattice::step
  Eigen::Matrix3d lattice_to_poses = Eigen::Matrix3d::Identity();  ///< SampleLattice::lattice_to_poses
  std::string lattice_origin;             ///< SampleLattice::origin
  std::string lattice_frame;              ///< SampleLattice::frame
};

PositionMaps position_maps(const Problem& problem, const SampleRecords& records);

/// maps.csv: position, x, y, z, samples, one column per objective (empty = undefined).
std::string maps_csv(const PositionMaps& maps);

/// Writes map_<objective>.{dat,gp,png,svg} into `directory` (slices by height above the lattice's
/// origin, the vertical z of the poses' frame, for lattice scenes;
/// otherwise an x-y scatter per z layer, highest first: each distinct z up to 12, else 12 equal bands). \return the file names of the plots rendered, and in `message`
/// why some were not (gnuplot missing or failing; the data and scripts are written regardless).
std::vector<std::string> plot_maps(const PositionMaps& maps, const std::string& directory, std::string& message);

}  // namespace hapsyn
