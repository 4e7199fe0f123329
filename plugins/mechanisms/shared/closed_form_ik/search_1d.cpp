// The 6R whose axes 5 and 6 meet (six_r_ik.hpp): a 1-D search over q1. For each q1 the point
// where axes 5 and 6 meet gives (q2, q3, q4) by SP5; the error e(q1) of each branch is zero
// where the rest of the orientation can be reached by q5 and q6 (one of IK-Geo's 1-D search
// cases).
#include "shared/closed_form_ik/families.hpp"
#include "shared/closed_form_ik/subproblems.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace hapsyn::plugins::closed_form_ik::detail {

namespace {

struct Branch {
  double q2 = 0, q3 = 0, q4 = 0, e = 0;
};

struct Sample {
  double q1 = 0;
  std::array<Branch, 4> branch{};
  int count = 0;
};

// What does not change with q1 for one target.
struct Problem {
  const PoeChain& c;
  Eigen::Matrix3d r06;
  Eigen::Vector3d pw;    // the point where axes 5 and 6 meet, now
  Eigen::Vector3d p3w;   // from joint 4 to that point at q = 0
  double cos56;          // h5 . h6
  Eigen::Vector3d r06_h6;  // axis 6 now
};

// R(k, theta) v (Rodrigues).
Eigen::Vector3d rotate(const Eigen::Vector3d& k, double theta, const Eigen::Vector3d& v) {
  const double c = std::cos(theta), s = std::sin(theta);
  return v * c + k.cross(v) * s + k * (k.dot(v) * (1 - c));
}

double wrapped(double a) { return a - 2 * M_PI * std::nearbyint(a / (2 * M_PI)); }

double distance2(const Branch& a, const Branch& b) {
  const double d2 = wrapped(a.q2 - b.q2), d3 = wrapped(a.q3 - b.q3), d4 = wrapped(a.q4 - b.q4);
  return d2 * d2 + d3 * d3 + d4 * d4;
}

// The branches at q1: R(h1, -q1) (p_w - p_01) - p_12 = R(h2, q2) (p_23 + R(h3, q3) (p_34 + R(h4, q4) p_4w)),
// i.e. SP5 with p0 = -p_23, k1 = h2 (theta1 = -q2), p1 = R(h1, -q1) (p_w - p_01) - p_12, k2 = h3,
// p2 = p_34, k3 = h4, p3 = p_4w; then each branch's e.
Sample evaluate(const Problem& pr, double q1) {
  const auto& h = pr.c.h;
  const auto& p = pr.c.p;
  Sample s;
  s.q1 = q1;
  const Eigen::Matrix3d r1 = rot(h[0], q1);
  const Eigen::Vector3d d = r1.transpose() * (pr.pw - p[0]) - p[1];
  const Angles3 a = sp5(-p[2], d, p[3], pr.p3w, h[1], h[2], h[3]);
  if (a.least_squares) return s;
  for (int i = 0; i < a.count; ++i) {
    const std::size_t k = static_cast<std::size_t>(i);
    Branch& b = s.branch[static_cast<std::size_t>(s.count++)];
    b.q2 = -a.theta1[k], b.q3 = a.theta2[k], b.q4 = a.theta3[k];
    // e = (R_04 h5) . (R_06 h6) - h5 . h6, R_04 h5 by rotating the vector (no matrices).
    const Eigen::Vector3d v = r1 * rotate(h[1], b.q2, rotate(h[2], b.q3, rotate(h[3], b.q4, h[4])));
    b.e = v.dot(pr.r06_h6) - pr.cos56;
  }
  return s;
}

// The branch of s nearest to ref (count > 0).
const Branch& nearest(const Sample& s, const Branch& ref) {
  int best = 0;
  for (int i = 1; i < s.count; ++i) {
    if (distance2(s.branch[static_cast<std::size_t>(i)], ref) < distance2(s.branch[static_cast<std::size_t>(best)], ref)) best = i;
  }
  return s.branch[static_cast<std::size_t>(best)];
}

Branch interpolate(const Branch& a, const Branch& b, double t) {
  Branch m;
  m.q2 = a.q2 + t * wrapped(b.q2 - a.q2);
  m.q3 = a.q3 + t * wrapped(b.q3 - a.q3);
  m.q4 = a.q4 + t * wrapped(b.q4 - a.q4);
  return m;
}

// The candidate at (q1, branch): (q5, q6) from the orientation left by joints 1 to 4.
void finish(const Problem& pr, double q1, const Branch& b, IkScratch& out) {
  const auto& h = pr.c.h;
  const Eigen::Matrix3d r04 = rot(h[0], q1) * rot(h[1], b.q2) * rot(h[2], b.q3) * rot(h[3], b.q4);
  // R(h5, q5) R(h6, q6) = R_04^T R_06 =: r46: R(h5, q5) h6 = r46 h6 and R(h6, -q6) h5 = r46^T h5.
  const Eigen::Matrix3d r46 = r04.transpose() * pr.r06;
  Vector6d q;
  q << q1, b.q2, b.q3, b.q4, sp1(h[5], r46 * h[5], h[4]).theta[0], -sp1(h[4], r46.transpose() * h[4], h[5]).theta[0];
  push(out, q);
}

// A root of one branch's e in [x0, x1] (opposite signs at the ends) by the Illinois method; the
// branch is followed by the nearest solution to the interpolation of its ends.
void refine(const Problem& pr, double x0, Branch b0, double x1, Branch b1, IkScratch& out) {
  double fa = b0.e, fb = b1.e;
  Branch root = std::abs(fa) < std::abs(fb) ? b0 : b1;
  double x = std::abs(fa) < std::abs(fb) ? x0 : x1;
  for (int it = 0; it < 60 && std::abs(x1 - x0) > 1e-8 && std::abs(fb) > 1e-10; ++it) {
    x = x1 - fb * (x1 - x0) / (fb - fa);
    const Sample s = evaluate(pr, x);
    if (s.count == 0) break;
    const Branch& m = nearest(s, interpolate(b0, b1, (x - x0) / (x1 - x0)));
    root = m;
    if (m.e * fb < 0) {
      x0 = x1, fa = fb, b0 = b1;
    } else {
      fa /= 2;
    }
    x1 = x, fb = m.e, b1 = m;
    if (m.e == 0.0) break;
  }
  finish(pr, x, root, out);
}

// Two close roots between samples (e rises to cross zero and falls back within one or two
// steps): the parabola through the branch's e at three neighbouring samples predicts a vertex
// beyond zero; e at the vertex then brackets a root on each side.
void touching(const Problem& pr, const Sample& before, const Sample& a, const Branch& ba, const Sample& b,
              const Branch& bb, IkScratch& out) {
  const Branch& bz = nearest(before, ba);
  const double slope = (bb.e - bz.e) / 2, curvature = (bb.e + bz.e) / 2 - ba.e;
  if (curvature == 0.0 || (curvature < 0) != (ba.e < 0)) return;  // curving away from zero
  const double t = -slope / (2 * curvature);
  if (t < -1.0 || t > 1.0 || ((ba.e - slope * slope / (4 * curvature)) < 0) == (ba.e < 0)) return;
  const double step = b.q1 - a.q1;
  const Sample v = evaluate(pr, a.q1 + t * step);
  if (v.count == 0) return;
  const Branch& bv = nearest(v, t >= 0 ? interpolate(ba, bb, t) : interpolate(ba, bz, -t));
  if ((bv.e < 0) == (ba.e < 0)) return;
  if (t >= 0) {
    refine(pr, a.q1, ba, v.q1, bv, out);
    refine(pr, v.q1, bv, b.q1, bb, out);
  } else {
    refine(pr, before.q1, bz, v.q1, bv, out);
    refine(pr, v.q1, bv, a.q1, ba, out);
  }
}

// Branches of neighbouring samples are matched greedily, nearest pairs first, up to this squared
// distance in (q2, q3, q4) [rad^2]; a branch left unmatched begins or ends between the samples
// (at a fold of the 3R position problem, where two branches meet) or jumps.
constexpr double kMatch2 = 0.25;
// Intervals with unmatched branches are halved up to this many times (1/64 of a sample step).
constexpr int kDepth = 6;

struct Matching {
  std::array<int, 4> partner{-1, -1, -1, -1};  // partner[i]: b's branch matched to a's branch i
  std::array<bool, 4> used_b{};
  bool complete = true;  // every branch of both samples matched
};

Matching match(const Sample& a, const Sample& b) {
  Matching m;
  for (int pairs = std::min(a.count, b.count); pairs > 0; --pairs) {
    int bi = -1, bj = -1;
    double best = kMatch2;
    for (int i = 0; i < a.count; ++i) {
      for (int j = 0; j < b.count; ++j) {
        if (m.partner[static_cast<std::size_t>(i)] >= 0 || m.used_b[static_cast<std::size_t>(j)]) continue;
        const double d = distance2(a.branch[static_cast<std::size_t>(i)], b.branch[static_cast<std::size_t>(j)]);
        if (d <= best) best = d, bi = i, bj = j;
      }
    }
    if (bi < 0) break;
    m.partner[static_cast<std::size_t>(bi)] = bj;
    m.used_b[static_cast<std::size_t>(bj)] = true;
  }
  for (int i = 0; i < a.count; ++i) m.complete = m.complete && m.partner[static_cast<std::size_t>(i)] >= 0;
  for (int j = 0; j < b.count; ++j) m.complete = m.complete && m.used_b[static_cast<std::size_t>(j)];
  return m;
}

// Roots between neighbouring samples a and b (before: the sample one step before a, or an empty
// one). An interval where a branch is left unmatched is halved (kDepth times at most); a matched
// pair whose e changes sign brackets a root (refine), one whose e nears zero and turns back may
// hide two (touching). At the last halving, the unmatched branches are close to their fold,
// where e is continuous from one branch of the pair to the other and a root near it is within
// reach of the Newton polish: they become candidates themselves.
void scan(const Problem& pr, const Sample& before, const Sample& a, const Sample& b, int depth, IkScratch& out) {
  const Matching m = match(a, b);
  if (!m.complete && depth > 0) {
    const Sample mid = evaluate(pr, 0.5 * (a.q1 + b.q1));
    const Sample none;
    scan(pr, none, a, mid, depth - 1, out);
    scan(pr, none, mid, b, depth - 1, out);
    return;
  }
  for (int i = 0; i < a.count; ++i) {
    const Branch& ba = a.branch[static_cast<std::size_t>(i)];
    const int j = m.partner[static_cast<std::size_t>(i)];
    if (j < 0) {
      finish(pr, a.q1, ba, out);
      continue;
    }
    const Branch& bb = b.branch[static_cast<std::size_t>(j)];
    if ((ba.e < 0) != (bb.e < 0) || ba.e == 0.0) {
      refine(pr, a.q1, ba, b.q1, bb, out);
    } else if (before.count > 0) {
      touching(pr, before, a, ba, b, bb, out);
    }
  }
  for (int j = 0; j < b.count; ++j) {
    if (!m.used_b[static_cast<std::size_t>(j)]) finish(pr, b.q1, b.branch[static_cast<std::size_t>(j)], out);
  }
}

}  // namespace

void search_1d_candidates(const PoeChain& c, const Eigen::Vector3d& point, const Eigen::Isometry3d& target,
                          int samples, IkScratch& s) {
  const Eigen::Matrix3d r06 = target.linear() * c.r_tool.transpose();
  const Eigen::Vector3d tool0 = c.joint_point(5) + c.p[6];
  const Problem pr{c, r06, target.translation() - r06 * (tool0 - point), point - c.joint_point(3), c.h[4].dot(c.h[5]),
                   r06 * c.h[5]};
  const double step = 2 * M_PI / samples;
  const Sample first = evaluate(pr, -M_PI);
  Sample before = evaluate(pr, -M_PI - step), prev = first;
  for (int k = 1; k <= samples; ++k) {
    Sample cur = k < samples ? evaluate(pr, -M_PI + k * step) : first;
    cur.q1 = -M_PI + k * step;  // the last interval ends at pi, the first sample's angle + 2 pi
    scan(pr, before, prev, cur, kDepth, s);
    before = prev;
    prev = cur;
  }
}

}  // namespace hapsyn::plugins::closed_form_ik::detail
