// The five-bar's block kernel, written with Google Highway (libhwy-dev): the same code is
// compiled for AVX-512, AVX2, SSE4 and baseline x86-64 (and other architectures' vector units),
// and HWY_DYNAMIC_DISPATCH picks the best one the CPU has, once, at the first call. One sample
// per lane; a block of kBlockLanes samples is one AVX-512 vector, two AVX2 vectors.
//
// Its arithmetic is the scalar model's (fivebar.cpp), operation for operation, and the file is
// compiled without floating-point contraction (CMakeLists.txt): the results are the scalar
// model's bit for bit, so that the model stays exactly mirror-symmetric (ties between mirrored
// samples, and with them the critical samples, are decided as on the per-sample path).
//
// Why no joint angles: the scalar model classifies with q1..q4 (atan2, acos), which costs more
// than the rest of a sample. For a sample that is not singular (every transmission sine at
// least singularity_tolerance = 1e-4, far above the 1e-9 rad angle tolerance), the paper's G is
// equivalent to sign tests on the link vectors of each leg, in its own (possibly mirrored) frame
// (KERNELS.md section 13.2):
//   - the free link points up: w_y >= -tan(1e-9) max(w_x, 0)     (q2 >= -t and q2 not above pi)
//   - the actuated link does not point below the horizon on a branch that makes q1 negative:
//     not (u_y < 0 and atan2(d) < 0)                            (q2 <= q1 + t)
//   - the working mode: sin(q3 - q2) > 0.
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "fivebar_block.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

#include "fivebar_block.hpp"

#include <cmath>
#include <cstddef>
#include <limits>

HWY_BEFORE_NAMESPACE();
namespace hapsyn::plugins {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

using D = hn::CappedTag<double, kBlockLanes>;  // at most a block per vector
using V = hn::Vec<D>;
using M = hn::Mask<D>;

constexpr double kEps = std::numeric_limits<double>::epsilon();
// tan(kFiveBarAngleTolerance); tan(1e-9) rounds to 1e-9.
constexpr double kTanAngleTolerance = 1e-9;
// fivebar.cpp's rounding bound of the leg's area term, in units of spread^2.
constexpr double kAreaTolerance = 32.0 * kEps;

// One leg in its own frame, for the lanes of one vector.
struct Leg {
  V ux, uy;  // unit vector along the actuated link
  V wx, wy;  // free link vector E - B [m]
  M solved;    // an IK solution exists
  M on_joint;  // E on the actuated joint of a folded leg (l1 = l2): singular
  M upright;   // the leg's part of G holds (see the file comment)
};

// Elbow-out inverse kinematics of one leg with E - A = (dx, dy): fivebar.cpp's solve_leg minus
// the angles (Heron's form of the law of cosines: one square root and one division).
HWY_INLINE Leg SolveLeg(D d, V dx, V dy, double l1, double l2) {
  const double diff = (l1 - l2) * (l1 + l2), sum = l1 + l2, fold = l1 - l2;
  const V zero = hn::Zero(d), one = hn::Set(d, 1.0);
  const V rho2 = hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy));
  const V spread = hn::Add(hn::Set(d, l1 * l1 + l2 * l2), rho2);
  const V area = hn::Mul(hn::Sub(hn::Set(d, sum * sum), rho2), hn::Sub(rho2, hn::Set(d, fold * fold)));
  const V tolerance = hn::Mul(hn::Mul(hn::Set(d, kAreaTolerance), spread), spread);
  const M positive = hn::Gt(rho2, zero);
  Leg leg;
  leg.on_joint = hn::AndNot(positive, hn::Le(hn::Set(d, std::abs(diff)), hn::Mul(hn::Set(d, 8.0 * kEps), spread)));
  leg.solved = hn::And(positive, hn::Ge(area, hn::Neg(tolerance)));
  const V root = hn::Sqrt(hn::IfThenElse(hn::Gt(area, zero), area, zero));
  const V along = hn::Add(hn::Set(d, diff), rho2);
  const V inv = hn::Div(one, hn::Mul(hn::Set(d, 2.0 * l1), hn::IfThenElse(positive, rho2, one)));
  leg.ux = hn::Mul(hn::Sub(hn::Mul(along, dx), hn::Mul(root, dy)), inv);
  leg.uy = hn::Mul(hn::Add(hn::Mul(along, dy), hn::Mul(root, dx)), inv);
  const V l1v = hn::Set(d, l1);
  leg.wx = hn::Sub(dx, hn::Mul(l1v, leg.ux));
  leg.wy = hn::Sub(dy, hn::Mul(l1v, leg.uy));
  // atan2(dy, dx) < 0: dy < 0, or dy = -0 with dx < 0 (atan2(-0, -1) = -pi).
  const M negative_zero = hn::And(hn::Eq(dy, zero), hn::Lt(hn::CopySign(one, dy), zero));
  const M below = hn::Or(hn::Lt(dy, zero), hn::And(negative_zero, hn::Lt(dx, zero)));
  const M free_up = hn::Ge(leg.wy, hn::Mul(hn::Set(d, -kTanAngleTolerance), hn::Max(leg.wx, zero)));
  leg.upright = hn::AndNot(hn::And(hn::Lt(leg.uy, zero), below), free_up);
  return leg;
}

// Status per lane (SampleStatus as a double: 0 reachable, 1 unreachable, 2 singular, 3 invalid).
HWY_INLINE V Classify(D d, const FiveBarBlockDesign& design, const Leg& left, const Leg& right) {
  const V tol = hn::Set(d, design.singularity_tolerance);
  const V inv_l2 = hn::Set(d, 1.0 / design.l2);
  const V s12 = hn::Mul(hn::Sub(hn::Mul(left.wx, left.uy), hn::Mul(left.wy, left.ux)), inv_l2);
  const V s34 = hn::Mul(hn::Sub(hn::Mul(right.wx, right.uy), hn::Mul(right.wy, right.ux)), inv_l2);
  const V cross12 = hn::Sub(hn::Mul(left.wx, right.wy), hn::Mul(left.wy, hn::Neg(right.wx)));
  const V s23 = hn::Mul(cross12, hn::Set(d, 1.0 / (design.l2 * design.l2)));
  const M unreachable = hn::Or(hn::Not(hn::Or(left.solved, left.on_joint)), hn::Not(hn::Or(right.solved, right.on_joint)));
  const M transmits = hn::And(hn::And(hn::Ge(hn::Abs(s12), tol), hn::Ge(hn::Abs(s34), tol)), hn::Ge(hn::Abs(s23), tol));
  const M singular = hn::Or(hn::Or(left.on_joint, right.on_joint), hn::Not(transmits));
  const M valid = hn::And(hn::And(left.upright, right.upright), hn::Gt(s23, hn::Zero(d)));
  return hn::IfThenElse(unreachable, hn::Set(d, 1.0),
                        hn::IfThenElse(singular, hn::Set(d, 2.0), hn::IfThenElse(valid, hn::Zero(d), hn::Set(d, 3.0))));
}

// J, and on request D and M, for the lanes at offset `i` (fivebar.cpp's formulas, in Eigen's order).
HWY_INLINE void Dynamics(D d, const FiveBarBlockDesign& design, const Leg& left, const Leg& right, bool inertia,
                         bool mass, std::size_t i, QuantityBlock& out) {
  const V l1 = hn::Set(d, design.l1), minus_l1 = hn::Set(d, -design.l1), half = hn::Set(d, 0.5);
  const V inv_l2_squared = hn::Set(d, 1.0 / (design.l2 * design.l2));
  const V u1x = left.ux, u1y = left.uy, w1x = left.wx, w1y = left.wy;
  const V u4x = hn::Neg(right.ux), u4y = right.uy, w2x = hn::Neg(right.wx), w2y = right.wy;
  const V cross12 = hn::Sub(hn::Mul(w1x, w2y), hn::Mul(w1y, w2x));
  const V b1 = hn::Mul(l1, hn::Sub(hn::Mul(u1x, w1y), hn::Mul(u1y, w1x)));
  const V b2 = hn::Mul(l1, hn::Sub(hn::Mul(u4x, w2y), hn::Mul(u4y, w2x)));
  // Unreachable or singular lanes may divide by zero: their values are ignored (no trap).
  const V inv_det = hn::Div(hn::Set(d, 1.0), cross12);
  const V j00 = hn::Mul(hn::Mul(w2y, b1), inv_det), j01 = hn::Mul(hn::Mul(hn::Neg(w1y), b2), inv_det);
  const V j10 = hn::Mul(hn::Mul(hn::Neg(w2x), b1), inv_det), j11 = hn::Mul(hn::Mul(w1x, b2), inv_det);
  hn::StoreU(j00, d, out.jacobian[0] + i);
  hn::StoreU(j01, d, out.jacobian[1] + i);
  hn::StoreU(j10, d, out.jacobian[2] + i);
  hn::StoreU(j11, d, out.jacobian[3] + i);
  if (!inertia) return;
  // c_k = (p_k + J) / 2 with p1 = [[-l1 u1y, 0], [l1 u1x, 0]], p2 = [[0, -l1 u4y], [0, l1 u4x]].
  const V p1_00 = hn::Mul(minus_l1, u1y), p1_10 = hn::Mul(l1, u1x);
  const V p2_01 = hn::Mul(minus_l1, u4y), p2_11 = hn::Mul(l1, u4x);
  const V c1_00 = hn::Mul(half, hn::Add(p1_00, j00)), c1_01 = hn::Mul(half, j01);
  const V c1_10 = hn::Mul(half, hn::Add(p1_10, j10)), c1_11 = hn::Mul(half, j11);
  const V c2_00 = hn::Mul(half, j00), c2_01 = hn::Mul(half, hn::Add(p2_01, j01));
  const V c2_10 = hn::Mul(half, j10), c2_11 = hn::Mul(half, hn::Add(p2_11, j11));
  // a2 = (J - p1)^T (-w1y, w1x) / l2^2, a3 = (J - p2)^T (-w2y, w2x) / l2^2.
  const V v1x = hn::Neg(w1y), v2x = hn::Neg(w2y);
  const V a2_0 = hn::Mul(hn::Add(hn::Mul(hn::Sub(j00, p1_00), v1x), hn::Mul(hn::Sub(j10, p1_10), w1x)), inv_l2_squared);
  const V a2_1 = hn::Mul(hn::Add(hn::Mul(j01, v1x), hn::Mul(j11, w1x)), inv_l2_squared);
  const V a3_0 = hn::Mul(hn::Add(hn::Mul(j00, v2x), hn::Mul(j10, w2x)), inv_l2_squared);
  const V a3_1 = hn::Mul(hn::Add(hn::Mul(hn::Sub(j01, p2_01), v2x), hn::Mul(hn::Sub(j11, p2_11), w2x)), inv_l2_squared);
  // D = m2 (c1^T c1 + c2^T c2) + I_f (a2 a2^T + a3 a3^T), plus I_a on the diagonal.
  const V m2 = hn::Set(d, design.m2), inertia_f = hn::Set(d, design.inertia_f), inertia_a = hn::Set(d, design.inertia_a);
  const auto dot2 = [](V a, V b, V c, V e) { return hn::Add(hn::Mul(a, b), hn::Mul(c, e)); };
  const auto entry = [&](V c1_0, V c1_1, V c2_0, V c2_1, V c1_2, V c1_3, V c2_2, V c2_3, V a_0, V a_1, V b_0, V b_1) {
    return hn::Add(hn::Mul(m2, hn::Add(dot2(c1_0, c1_1, c1_2, c1_3), dot2(c2_0, c2_1, c2_2, c2_3))),
                   hn::Mul(inertia_f, dot2(a_0, a_1, b_0, b_1)));
  };
  const V d00 = hn::Add(entry(c1_00, c1_00, c2_00, c2_00, c1_10, c1_10, c2_10, c2_10, a2_0, a2_0, a3_0, a3_0), inertia_a);
  const V d01 = entry(c1_00, c1_01, c2_00, c2_01, c1_10, c1_11, c2_10, c2_11, a2_0, a2_1, a3_0, a3_1);
  const V d11 = hn::Add(entry(c1_01, c1_01, c2_01, c2_01, c1_11, c1_11, c2_11, c2_11, a2_1, a2_1, a3_1, a3_1), inertia_a);
  hn::StoreU(d00, d, out.inertia[0] + i);
  hn::StoreU(d01, d, out.inertia[1] + i);
  hn::StoreU(d01, d, out.inertia[2] + i);
  hn::StoreU(d11, d, out.inertia[3] + i);
  if (!mass) return;
  // M = (K^T D) K with K = J^-1 = [[w1x / b1, w1y / b1], [w2x / b2, w2y / b2]].
  const V inv_b1 = hn::Div(hn::Set(d, 1.0), b1), inv_b2 = hn::Div(hn::Set(d, 1.0), b2);
  const V k00 = hn::Mul(w1x, inv_b1), k01 = hn::Mul(w1y, inv_b1), k10 = hn::Mul(w2x, inv_b2), k11 = hn::Mul(w2y, inv_b2);
  const V t00 = dot2(k00, d00, k10, d01), t01 = dot2(k00, d01, k10, d11);
  const V t10 = dot2(k01, d00, k11, d01), t11 = dot2(k01, d01, k11, d11);
  hn::StoreU(dot2(t00, k00, t01, k10), d, out.effective_mass[0] + i);
  hn::StoreU(dot2(t00, k01, t01, k11), d, out.effective_mass[1] + i);
  hn::StoreU(dot2(t10, k00, t11, k10), d, out.effective_mass[2] + i);
  hn::StoreU(dot2(t10, k01, t11, k11), d, out.effective_mass[3] + i);
}

void SolveFiveBarBlock(const FiveBarBlockDesign& design, const double* x, const double* y, bool jacobian,
                       bool inertia, bool mass, QuantityBlock& out) {
  const D d;
  const std::size_t n = hn::Lanes(d);
  HWY_ALIGN double status[kBlockLanes];
  for (std::size_t i = 0; i < static_cast<std::size_t>(kBlockLanes); i += n) {
    const V px = hn::LoadU(d, x + i);
    const V ey = hn::Add(hn::LoadU(d, y + i), hn::Set(d, design.r));
    const V h0 = hn::Set(d, design.h0);
    const Leg left = SolveLeg(d, hn::Add(px, h0), ey, design.l1, design.l2);
    const Leg right = SolveLeg(d, hn::Sub(h0, px), ey, design.l1, design.l2);  // mirrored about x = 0
    const V lane_status = Classify(d, design, left, right);
    hn::Store(lane_status, d, status + i);
    // The quantities of lanes that are not reachable are never read (QuantityBlock's contract):
    // when no lane is, they are not computed.
    if (jacobian && !hn::AllFalse(d, hn::Eq(lane_status, hn::Zero(d)))) Dynamics(d, design, left, right, inertia, mass, i, out);
  }
  for (int i = 0; i < kBlockLanes; ++i) out.status[i] = static_cast<std::int32_t>(status[i]);
}

}  // namespace HWY_NAMESPACE
}  // namespace hapsyn::plugins
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace hapsyn::plugins {

HWY_EXPORT(SolveFiveBarBlock);

void solve_fivebar_block(const FiveBarBlockDesign& design, const double* x, const double* y, Needs needs,
                         QuantityBlock& out) {
  const bool jacobian = (needs & (kNeedJacobian | kNeedInertia | kNeedEffectiveMass)) != 0;
  out.jacobian_rows = out.jacobian_cols = jacobian ? 2 : 0;
  out.inertia_size = (needs & (kNeedInertia | kNeedEffectiveMass)) ? 2 : 0;
  out.effective_mass_size = (needs & kNeedEffectiveMass) ? 2 : 0;
  HWY_DYNAMIC_DISPATCH(SolveFiveBarBlock)(design, x, y, jacobian, out.inertia_size > 0, out.effective_mass_size > 0, out);
}

const char* fivebar_block_target() {
  const std::int64_t targets = hwy::SupportedTargets() & HWY_TARGETS;
  return hwy::TargetName(targets & -targets);  // the lowest bit is the best target, the one dispatched to
}

}  // namespace hapsyn::plugins
#endif
