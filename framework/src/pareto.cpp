#include <hapsyn/error.hpp>
#include <hapsyn/pareto.hpp>

#include <pagmo/utils/hypervolume.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace hapsyn {

namespace {
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// +1 when larger is better, -1 when smaller is.
double sign_of(Sense s) { return s == Sense::kMaximize ? 1.0 : -1.0; }

double euclidean(const ObjectivePoint& a, const ObjectivePoint& b) {
  double d2 = 0.0;
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) d2 += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(d2);
}

double nearest_distance(const ObjectivePoint& p, const std::vector<ObjectivePoint>& set) {
  double nearest = kInf;
  for (const ObjectivePoint& q : set) nearest = std::min(nearest, euclidean(p, q));
  return nearest;
}

Json number_or_null(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }
}  // namespace

bool dominates(const ObjectivePoint& a, const ObjectivePoint& b, const std::vector<Sense>& senses) {
  bool better = false;
  for (std::size_t i = 0; i < senses.size(); ++i) {
    const double da = sign_of(senses[i]) * a[i];
    const double db = sign_of(senses[i]) * b[i];
    if (da < db) return false;
    if (da > db) better = true;
  }
  return better;
}

std::vector<std::size_t> non_dominated(const std::vector<ObjectivePoint>& points, const std::vector<Sense>& senses) {
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < points.size(); ++i) {
    bool keep = true;
    for (std::size_t j = 0; j < points.size() && keep; ++j) {
      if (j == i) continue;
      if (dominates(points[j], points[i], senses)) keep = false;
      if (j < i && points[j] == points[i]) keep = false;  // duplicates: the first stays
    }
    if (keep) kept.push_back(i);
  }
  return kept;
}

std::vector<std::vector<double>> simplex_grid(int objectives, int divisions) {
  if (objectives < 1) throw Error("pareto", "simplex grid: objectives = " + std::to_string(objectives) + ": must be >= 1");
  if (divisions < 0) throw Error("pareto", "simplex grid: divisions = " + std::to_string(divisions) + ": must be >= 0");
  // C(divisions + m - 1, m - 1), guarded against overflow.
  double count = 1.0;
  for (int k = 1; k < objectives; ++k) count = count * (divisions + k) / k;
  if (count > 1e6) {
    throw Error("pareto", "simplex grid: " + std::to_string(divisions) + " divisions for " + std::to_string(objectives) +
                              " objectives give " + std::to_string(static_cast<long long>(count)) +
                              " points; at most 1000000 are allowed");
  }
  std::vector<std::vector<double>> grid;
  std::vector<int> k(static_cast<std::size_t>(objectives), 0);
  // Recursive enumeration, k_0 descending, then k_1 descending, ...
  const auto recurse = [&](const auto& self, int index, int left) -> void {
    if (index == objectives - 1) {
      k[static_cast<std::size_t>(index)] = left;
      std::vector<double> beta(static_cast<std::size_t>(objectives));
      for (int i = 0; i < objectives; ++i) {
        beta[static_cast<std::size_t>(i)] = divisions == 0 ? 1.0 / objectives : static_cast<double>(k[static_cast<std::size_t>(i)]) / divisions;
      }
      grid.push_back(beta);
      return;
    }
    for (int v = left; v >= 0; --v) {
      k[static_cast<std::size_t>(index)] = v;
      self(self, index + 1, left - v);
    }
  };
  recurse(recurse, 0, divisions);
  if (divisions == 0) grid.resize(1);
  return grid;
}

double hypervolume(const std::vector<ObjectivePoint>& front, const ObjectivePoint& reference,
                   const std::vector<Sense>& senses) {
  const std::size_t m = senses.size();
  if (reference.size() != m) {
    throw Error("pareto", "hypervolume: the reference point has " + std::to_string(reference.size()) +
                              " values for " + std::to_string(m) + " objectives");
  }
  for (double r : reference) {
    if (!std::isfinite(r)) throw Error("pareto", "hypervolume: the reference point must be finite");
  }
  // pagmo minimizes: flip maximized objectives; keep only points strictly better than the
  // reference in every objective (the others bound an empty box).
  std::vector<pagmo::vector_double> points;
  pagmo::vector_double ref(m);
  for (std::size_t i = 0; i < m; ++i) ref[i] = -sign_of(senses[i]) * reference[i];
  for (const ObjectivePoint& p : front) {
    if (p.size() != m) throw Error("pareto", "hypervolume: a point has " + std::to_string(p.size()) + " values for " + std::to_string(m) + " objectives");
    pagmo::vector_double q(m);
    bool inside = true;
    for (std::size_t i = 0; i < m; ++i) {
      if (!std::isfinite(p[i])) throw Error("pareto", "hypervolume: a front point is not finite");
      q[i] = -sign_of(senses[i]) * p[i];
      inside = inside && q[i] < ref[i];
    }
    if (inside) points.push_back(q);
  }
  if (points.empty()) return 0.0;
  if (m == 1) {
    double best = ref[0];
    for (const auto& q : points) best = std::min(best, q[0]);
    return ref[0] - best;
  }
  const pagmo::hypervolume hv(points, false);
  return hv.compute(ref);
}

double spacing(const std::vector<ObjectivePoint>& front) {
  const std::size_t n = front.size();
  if (n < 2) return kNan;
  std::vector<double> d(n, kInf);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < n; ++j) {
      if (i == j) continue;
      double l1 = 0.0;
      for (std::size_t k = 0; k < front[i].size(); ++k) l1 += std::abs(front[i][k] - front[j][k]);
      d[i] = std::min(d[i], l1);
    }
  }
  double mean = 0.0;
  for (double v : d) mean += v;
  mean /= static_cast<double>(n);
  double sum = 0.0;
  for (double v : d) sum += (v - mean) * (v - mean);
  return std::sqrt(sum / static_cast<double>(n - 1));
}

double generational_distance(const std::vector<ObjectivePoint>& front, const std::vector<ObjectivePoint>& reference) {
  if (front.empty()) return kNan;
  if (reference.empty()) return kInf;
  double sum = 0.0;
  for (const ObjectivePoint& p : front) sum += nearest_distance(p, reference);
  return sum / static_cast<double>(front.size());
}

double inverted_generational_distance(const std::vector<ObjectivePoint>& front,
                                      const std::vector<ObjectivePoint>& reference) {
  if (reference.empty()) return 0.0;
  if (front.empty()) return kInf;
  double sum = 0.0;
  for (const ObjectivePoint& r : reference) sum += nearest_distance(r, front);
  return sum / static_cast<double>(reference.size());
}

std::vector<double> domination_gap(const ObjectivePoint& point, const std::vector<ObjectivePoint>& others,
                                   const std::vector<Sense>& senses) {
  std::vector<double> gap(senses.size(), 0.0);
  for (const ObjectivePoint& q : others) {
    if (!dominates(q, point, senses)) continue;
    for (std::size_t i = 0; i < senses.size(); ++i) gap[i] = std::max(gap[i], sign_of(senses[i]) * (q[i] - point[i]));
  }
  return gap;
}

Json front_indicators(const IndicatorInputs& in) {
  Json out = Json::object();
  const std::size_t m = in.senses.size();
  out["points"] = in.front.size();
  if (!in.front.empty()) {
    Json extent = Json::object();
    for (std::size_t i = 0; i < m; ++i) {
      double lo = kInf, hi = -kInf;
      for (const ObjectivePoint& p : in.front) {
        lo = std::min(lo, p[i]);
        hi = std::max(hi, p[i]);
      }
      extent[in.names[i]] = {lo, hi};
    }
    out["extent"] = extent;
    const double s = spacing(in.front);
    out["spacing"] = number_or_null(s);
    // Relative spacing: spacing over the mean nearest-neighbour distance (scale-free).
    double mean_nn = kNan;
    if (in.front.size() >= 2) {
      mean_nn = 0.0;
      for (std::size_t i = 0; i < in.front.size(); ++i) {
        double d = kInf;
        for (std::size_t j = 0; j < in.front.size(); ++j) {
          if (i == j) continue;
          double l1 = 0.0;
          for (std::size_t k = 0; k < m; ++k) l1 += std::abs(in.front[i][k] - in.front[j][k]);
          d = std::min(d, l1);
        }
        mean_nn += d;
      }
      mean_nn /= static_cast<double>(in.front.size());
    }
    out["spacing_relative"] = number_or_null(mean_nn > 0 ? s / mean_nn : kNan);
  }
  if (!in.reference_point.empty()) {
    out["reference_point"] = in.reference_point;
    out["hypervolume"] = in.front.empty() && in.best ? hypervolume({*in.best}, in.reference_point, in.senses)
                                                     : hypervolume(in.front, in.reference_point, in.senses);
  } else {
    out["hypervolume"] = nullptr;
  }
  if (!in.reference_front.empty()) {
    out["reference_front_points"] = in.reference_front.size();
    if (!in.front.empty()) {
      out["generational_distance"] = number_or_null(generational_distance(in.front, in.reference_front));
      out["inverted_generational_distance"] = number_or_null(inverted_generational_distance(in.front, in.reference_front));
      std::vector<double> worst(m, 0.0);
      long long dominated = 0;
      for (const ObjectivePoint& p : in.front) {
        const std::vector<double> gap = domination_gap(p, in.reference_front, in.senses);
        bool any = false;
        for (std::size_t i = 0; i < m; ++i) {
          worst[i] = std::max(worst[i], gap[i]);
          any = any || gap[i] > 0.0;
        }
        dominated += any ? 1 : 0;
      }
      Json w = Json::object();
      for (std::size_t i = 0; i < m; ++i) w[in.names[i]] = worst[i];
      out["max_domination_gap"] = w;
      out["dominated_points"] = dominated;
    }
    if (in.best) {
      const std::vector<double> gap = domination_gap(*in.best, in.reference_front, in.senses);
      bool any = false;
      Json g = Json::object();
      for (std::size_t i = 0; i < m; ++i) {
        g[in.names[i]] = gap[i];
        any = any || gap[i] > 0.0;
      }
      out["best_dominated"] = any;
      out["best_domination_gap"] = g;
    }
  }
  return out;
}

std::vector<ObjectivePoint> front_of_result(const Json& result, const std::vector<std::string>& names,
                                            const std::string& source) {
  if (!result.is_object() || !result.contains("front") || !result["front"].is_array()) {
    throw Error("indicators", source + ": has no \"front\" array (is it the result.json of a Pareto study?)");
  }
  std::vector<ObjectivePoint> points;
  for (std::size_t k = 0; k < result["front"].size(); ++k) {
    const Json& p = result["front"][k];
    ObjectivePoint v;
    for (const std::string& name : names) {
      if (!p.contains("objectives") || !p["objectives"].contains(name) || !p["objectives"][name].is_number()) {
        throw Error("indicators", source + ": front[" + std::to_string(k) + "].objectives." + name +
                                      ": missing (the reference front must have the study's objectives)");
      }
      v.push_back(p["objectives"][name].get<double>());
    }
    points.push_back(v);
  }
  return points;
}

}  // namespace hapsyn
