#pragma once
/// \file
/// Pareto fronts: dominance, non-dominated filtering, simplex grids and front-quality
/// indicators (hypervolume, spacing, generational distances, domination gaps).
///
/// Conventions. A *point* is a vector of objective values in their natural units, one per
/// objective; `senses` says per objective whether larger (kMaximize) or smaller (kMinimize) is
/// better. Every function takes the senses, so callers never flip signs themselves. Functions
/// that measure distances do so in natural units (for GII and GDI: dimensionless).
#include <hapsyn/json.hpp>
#include <hapsyn/problem.hpp>

#include <string>
#include <vector>

namespace hapsyn {

using ObjectivePoint = std::vector<double>;

/// True when `a` dominates `b`: at least as good in every objective and better in one.
/// \pre a.size() == b.size() == senses.size()
bool dominates(const ObjectivePoint& a, const ObjectivePoint& b, const std::vector<Sense>& senses);

/// Indices of the non-dominated points of `points`, in their original order. Of several
/// points with identical objective vectors only the first is kept (a front lists each trade-off
/// once). Any number of objectives; O(n^2 m).
std::vector<std::size_t> non_dominated(const std::vector<ObjectivePoint>& points, const std::vector<Sense>& senses);

/// Every point of the simplex grid {beta >= 0, sum beta = 1} with `divisions` steps per edge:
/// beta_i = k_i / divisions, in lexicographic order of (k_1, ..., k_m) descending from
/// (divisions, 0, ..., 0). C(divisions + m - 1, m - 1) points; for m = 2 they run from (1, 0) to
/// (0, 1). \throws Error("pareto", ...) when objectives < 1 or divisions < 0, or the grid would
/// exceed 1e6 points.
std::vector<std::vector<double>> simplex_grid(int objectives, int divisions);

/// Hypervolume dominated by `front` and bounded by `reference` (pagmo::hypervolume, exact).
/// Points that do not strictly improve on the reference in every objective add nothing.
/// 0 for an empty front. \throws Error("pareto", ...) on a size mismatch or non-finite value.
double hypervolume(const std::vector<ObjectivePoint>& front, const ObjectivePoint& reference,
                   const std::vector<Sense>& senses);

/// Schott's spacing: sqrt(sum_i (d_i - mean d)^2 / (n - 1)), d_i the L1 distance from point i to
/// its nearest other point. 0 for perfectly even spacing; NaN for fewer than 2 points.
double spacing(const std::vector<ObjectivePoint>& front);

/// Generational distance: mean over `front` of the Euclidean distance to the nearest point of
/// `reference` (how far the points lie from the reference front). Infinity when `reference` is
/// empty, NaN when `front` is.
double generational_distance(const std::vector<ObjectivePoint>& front, const std::vector<ObjectivePoint>& reference);

/// Inverted generational distance: mean over `reference` of the distance to the nearest point of
/// `front` (how well the front covers the reference front). Infinity when `front` is empty.
double inverted_generational_distance(const std::vector<ObjectivePoint>& front,
                                      const std::vector<ObjectivePoint>& reference);

/// How much `point` is dominated by `others`: per objective, the largest improvement in that
/// objective offered by a point of `others` that dominates `point` (0 when none dominates it).
/// Unal's Figure 7 reading: how much GII one gains at no loss of GDI, and vice versa.
std::vector<double> domination_gap(const ObjectivePoint& point, const std::vector<ObjectivePoint>& others,
                                   const std::vector<Sense>& senses);

/// Front-quality indicators of a study result, as written into result.json under "indicators".
struct IndicatorInputs {
  std::vector<std::string> names;        ///< objective names
  std::vector<Sense> senses;
  std::vector<ObjectivePoint> front;     ///< the study's front (may be empty)
  const ObjectivePoint* best = nullptr;  ///< the study's single design, if any
  std::vector<ObjectivePoint> reference_front;  ///< may be empty
  ObjectivePoint reference_point;        ///< may be empty (no hypervolume then)
};
/// {"points", "hypervolume", "reference_point", "spacing", "spacing_relative" (spacing / mean
/// nearest-neighbour distance), "extent" (per objective [min, max]), and with a reference front:
/// "generational_distance", "inverted_generational_distance", "max_domination_gap" (per
/// objective, over the front's points), "dominated_points"; for a single design with a
/// reference front: "best_dominated", "best_domination_gap" (per objective)}. Values that cannot
/// be computed are null.
Json front_indicators(const IndicatorInputs& inputs);

/// Objective points of a result document's "front" (in the order of `names`).
/// \throws Error("indicators", ...) naming `source` when the document has no such front or a
/// point lacks an objective.
std::vector<ObjectivePoint> front_of_result(const Json& result, const std::vector<std::string>& names,
                                            const std::string& source);

}  // namespace hapsyn
