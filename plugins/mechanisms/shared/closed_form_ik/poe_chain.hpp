#pragma once
/// \file
/// A revolute chain in product-of-exponentials form, as IK-Geo writes it (Elias & Wen 2022):
/// at q = 0 every joint frame is parallel to the base frame, joint i turns about
/// the unit axis h_i (base-frame coordinates) and sits at the offset p_{i-1,i} from joint i-1
/// (from the base origin for i = 1); the tool sits at p_{n,T} from joint n with the fixed
/// rotation R_{n,T}:
///
///   R_0T(q) = R(h_1, q_1) ... R(h_n, q_n) R_nT,
///   p_0T(q) = p_01 + R(h_1, q_1) p_12 + ... + R(h_1, q_1) ... R(h_n, q_n) p_nT.
///
/// The classifier finds the axis patterns the closed-form solvers use (intersecting and parallel
/// consecutive axes, spherical wrist, three consecutive parallel axes) and names the family
/// (EAIK, Ostermeier et al. 2025, derives the decomposition from the axes the same way).
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <array>
#include <string>
#include <vector>

namespace hapsyn::plugins::closed_form_ik {

/// Most joints of a PoeChain (the serial_chain mechanism's limit).
constexpr int kMaxJoints = 7;

/// A revolute chain in product-of-exponentials form (see the file comment). Plain data.
struct PoeChain {
  int n = 0;                                       ///< joints, 1..kMaxJoints
  std::array<Eigen::Vector3d, kMaxJoints> h{};     ///< h[i]: unit axis of joint i+1 (base frame, q = 0)
  std::array<Eigen::Vector3d, kMaxJoints + 1> p{};  ///< p[0] = p_01, p[i] = p_{i,i+1}, p[n] = p_nT [m]
  Eigen::Matrix3d r_tool = Eigen::Matrix3d::Identity();  ///< R_nT

  /// From local joint frames as the serial_chain mechanism stores them (chain.hpp):
  /// T_0T(q) = O_1 Rot(a_1, q_1) O_2 ... O_n Rot(a_n, q_n) T_tip, with origins[i] = O_{i+1} and
  /// axes[i] = a_{i+1} in joint frame i+1 (normalised here).
  /// \throws hapsyn::Error ("closed_form_ik") when the sizes differ, are 0 or exceed kMaxJoints,
  /// or an axis has zero length.
  static PoeChain from_local_frames(const std::vector<Eigen::Isometry3d>& origins,
                                    const std::vector<Eigen::Vector3d>& axes, const Eigen::Isometry3d& tip);

  /// Forward kinematics: the tool pose T_0T(q). \param q n joint angles [rad]. Allocation-free.
  Eigen::Isometry3d forward(const double* q) const;

  /// Forward kinematics and the geometric Jacobian of the tool point in the base frame, rows
  /// (omega, v), columns 0..n-1 (the rest untouched). Allocation-free.
  void forward_jacobian(const double* q, Eigen::Isometry3d& pose, Eigen::Matrix<double, 6, kMaxJoints>& jacobian) const;

  /// The position of joint i+1's frame origin at q = 0 (a point on axis h[i]).
  Eigen::Vector3d joint_point(int i) const;

  /// The chain of the inverse pose: reversed().forward(q') = forward(q)^-1 with q'_i = q_{n-1-i}
  /// (joint order reversed, axes h'_i = -R_nT^T h_{n-1-i}, offsets p'_i = -R_nT^T p_{n-i}, tool
  /// rotation R_nT^T).
  PoeChain reversed() const;
};

/// Which closed-form solver a 6R chain gets (ClosedFormIk6R).
enum class IkFamily {
  kSphericalWrist,     ///< axes 4, 5, 6 (or, reversed, 1, 2, 3) through one point: SP5 + SP2 + SP1
  kThreeParallel,      ///< axes 2, 3, 4 (or, reversed, 3, 4, 5) parallel (UR type): SP6 + SP1 + SP3
  kScaraPair,          ///< axes 1, 2, 3 parallel and 4 || 5 (or, reversed, 4, 5, 6 and 2 || 3; haptic 6R type): SP4 + SP1 + SP3
  kSearch1d,           ///< axes 5, 6 (or, reversed, 1, 2) intersect: 1-D search over joint 1 (6), SP5 inside
  kUnsupported,        ///< none of the above (IK-Geo's 2-D search cases; not implemented)
};

/// The axis patterns of a chain, to a tolerance.
struct ChainGeometry {
  int n = 0;
  /// parallel[i]: axes i+1 and i+2 parallel (or antiparallel).
  std::array<bool, kMaxJoints - 1> parallel{};
  /// intersecting[i]: axes i+1 and i+2 meet in one point (not parallel); at point[i] (q = 0).
  std::array<bool, kMaxJoints - 1> intersecting{};
  std::array<Eigen::Vector3d, kMaxJoints - 1> point{};
  bool spherical_wrist = false;     ///< the last three axes meet in one point (wrist_point)
  bool spherical_shoulder = false;  ///< the first three axes meet in one point (shoulder_point)
  Eigen::Vector3d wrist_point = Eigen::Vector3d::Zero(), shoulder_point = Eigen::Vector3d::Zero();
  /// Index (0-based) of the first of three consecutive parallel axes, -1 when there are none.
  int three_parallel = -1;
  IkFamily family = IkFamily::kUnsupported;  ///< the 6R solver (kUnsupported unless n = 6)
  bool reversed = false;  ///< the family's pattern is found on the reversed chain

  /// One line naming the patterns and the family, e.g.
  /// "6R: 2||3||4 (three parallel), 5x6; family: three parallel axes 2-3-4 (UR type)".
  std::string describe() const;
};

/// Classifies a chain. \param tolerance |h_i x h_j| below it is parallel; two lines closer than
/// tolerance times the chain's size (sum of |p_i|, at least 1 m) meet.
ChainGeometry classify(const PoeChain& chain, double tolerance = 1e-9);

}  // namespace hapsyn::plugins::closed_form_ik
