#pragma once
/// \file
/// Sample blocks: the optional block path of the per-sample loop. A mechanism whose model can
/// solve several samples at once (MechanismAcceleration::solve_block) and metrics that can compute
/// their local values for them at once (MetricAcceleration::local_block) let the evaluator handle
/// kBlockLanes samples per call, structure of arrays, so that the kernels run one sample per
/// SIMD lane. The evaluator reduces the lanes one by one in the scene's order, so a study gets
/// the same statuses, critical samples, pruning decisions and sample counts as on the
/// per-sample path (docs/design.md section 13); values agree to rounding (a block kernel need
/// not round like the scalar one).
#include <hapsyn/quantities.hpp>

#include <cstdint>

namespace hapsyn {

/// Samples per block: 8 doubles, one AVX-512 register (two AVX2 registers).
constexpr int kBlockLanes = 8;
static_assert(kBlockLanes == 8, "QuantityBlock::samples initialises 8 lanes");
/// Largest pose dimension the block path serves (x, y, z, qw, qx, qy, qz).
constexpr int kBlockMaxCoordinates = 7;
/// Largest side of a block matrix (J, D, M): kMaxTask x kMaxTask entries.
constexpr int kBlockMaxEntries = kMaxTask * kMaxTask;

/// The poses of up to kBlockLanes samples, structure of arrays.
struct PoseBlock {
  /// coordinate[c][lane]: coordinate c of the lane's sample, in the scene frame and units
  /// (as SampleSet::pose). Lanes at or beyond `count` hold copies of a valid sample (so that
  /// a kernel can compute every lane without producing values it must guard against).
  const double* coordinate[kBlockMaxCoordinates] = {};
  int dimension = 0;  ///< SampleSet::dimension()
  int count = 0;      ///< lanes that carry samples, 1..kBlockLanes
};

/// What a block kernel computes for up to kBlockLanes samples, structure of arrays. Matrices
/// are row-major per lane: entry (r, c) of lane i is matrix[r * cols + c][i].
struct QuantityBlock {
  alignas(64) std::int32_t status[kBlockLanes] = {};  ///< a SampleStatus per lane, always set
  int jacobian_rows = 0, jacobian_cols = 0;            ///< shape of J (kNeedJacobian)
  int inertia_size = 0;                                ///< side of D (kNeedInertia)
  int effective_mass_size = 0;                         ///< side of M (kNeedEffectiveMass)
  int gravity_size = 0;                                ///< joints of the gravity torque (kNeedGravity)
  int actuator_count = 0;                              ///< joints of the actuator limits (kNeedActuatorLimits)
  alignas(64) double jacobian[kBlockMaxEntries][kBlockLanes] = {};
  alignas(64) double inertia[kBlockMaxEntries][kBlockLanes] = {};
  alignas(64) double effective_mass[kBlockMaxEntries][kBlockLanes] = {};
  alignas(64) double gravity[kMaxTask][kBlockLanes] = {};  ///< [N m] per joint and lane
  double max_velocity[kMaxTask] = {};  ///< actuator velocity limits [rad/s]: the design's, the same for every lane
  double max_torque[kMaxTask] = {};    ///< actuator torque limits [N m]: the design's

  /// Set by the evaluator before each metric's local_block(), like SampleQuantities::sample and
  /// SampleQuantities::attributes: the scene index of each lane's sample (lanes at or beyond the
  /// block's count repeat a valid one; -1 outside the evaluator), and the scene attributes that
  /// metric lists in MetricSpecs::scene_attributes.
  int samples[kBlockLanes] = {-1, -1, -1, -1, -1, -1, -1, -1};
  const AttributeMatrix* const* attributes = nullptr;
  int attribute_count = 0;
  /// Also set by the evaluator with `attributes`, or null: the same attributes of this block's
  /// lanes, structure of arrays (attribute_lanes(k)). The evaluator keeps that copy for the
  /// blocks of the scene's visiting order; the blocks of a sample subset have none.
  const double* const* attribute_lane_data = nullptr;

  SampleStatus lane_status(int lane) const { return static_cast<SampleStatus>(status[lane]); }
  /// Row of lane `lane`'s sample in the calling metric's k-th scene attribute, or null when the
  /// evaluator did not resolve it.
  const double* attribute_row(int k, int lane) const {
    if (!attributes || k < 0 || k >= attribute_count || !attributes[k]) return nullptr;
    const int sample = samples[lane];
    return sample >= 0 && sample < attributes[k]->rows() ? attributes[k]->row(sample).data() : nullptr;
  }
  /// The calling metric's k-th scene attribute for all lanes at once, or null when the evaluator
  /// has no such copy (then read attribute_row() per lane): entry e of lane i at
  /// [e * kBlockLanes + i], e < attributes[k]->cols(), 64-byte aligned; the values are those of
  /// attribute_row(k, i), lanes at or beyond the block's count included.
  const double* attribute_lanes(int k) const {
    if (!attribute_lane_data || !attributes || k < 0 || k >= attribute_count) return nullptr;
    return attribute_lane_data[k];
  }
};

}  // namespace hapsyn
