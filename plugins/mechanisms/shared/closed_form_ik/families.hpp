#pragma once
// Internal to hapsyn_closed_form_ik: the family solvers of six_r_ik.hpp. Each appends its raw
// candidates (in the joint order of the chain it is given, least-squares ones included: the
// caller polishes and filters them) to scratch.
#include "shared/closed_form_ik/six_r_ik.hpp"

namespace hapsyn::plugins::closed_form_ik::detail {

/// Appends q unless the scratch is full.
inline void push(IkScratch& s, const Vector6d& q) {
  if (s.count < static_cast<int>(s.candidate.size())) s.candidate[static_cast<std::size_t>(s.count++)] = q;
}

/// Axes 4, 5, 6 meet at wrist (base frame, q = 0).
void spherical_wrist_candidates(const PoeChain& c, const Eigen::Vector3d& wrist, const Eigen::Isometry3d& target,
                                IkScratch& s);

/// Axes 2, 3, 4 parallel.
void three_parallel_candidates(const PoeChain& c, const Eigen::Isometry3d& target, IkScratch& s);

/// Axes 1, 2, 3 parallel and axes 4, 5 parallel.
void scara_pair_candidates(const PoeChain& c, const Eigen::Isometry3d& target, IkScratch& s);

/// Axes 5 and 6 meet at point (base frame, q = 0); samples of q1 as six_r_ik.hpp describes.
void search_1d_candidates(const PoeChain& c, const Eigen::Vector3d& point, const Eigen::Isometry3d& target,
                          int samples, IkScratch& s);

}  // namespace hapsyn::plugins::closed_form_ik::detail
