// Coverage's block path (KERNELS.md section 14.3): local() for kBlockLanes samples at once, one
// sample per lane. The elimination of J with partial pivoting picks each lane's own pivot row
// and swaps rows by lane-wise selection, so every lane takes the pivots local() takes.
#include "coverage.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/multiversion.hpp>

#include <cstdint>
#include <limits>
#include <string>

namespace hapsyn::plugins {

namespace {

constexpr const char* kName = "coverage";

// The lane's 6x6 row-major attribute (M_v or M_a); the errors are local()'s.
const double* lane_attribute(const QuantityBlock& q, int index, int lane, const char* name, const char* term) {
  const double* row = q.attribute_row(index, lane);
  if (!row || q.attributes[index]->cols() != 36) {
    throw Error(kName, std::string("the ") + term + " term needs the scene attribute " + name +
                           " (36 values per sample) of each lane's sample; the block does not provide it");
  }
  return row;
}

// Entry `e` of each lane's array, as lane vectors.
[[gnu::always_inline]] inline Lanes gather(const double* const (&rows)[kBlockLanes], int e) {
  Lanes r;
  for (int lane = 0; lane < kBlockLanes; ++lane) r.v[lane] = rows[lane][e];
  return r;
}

// The lanes' 6x6 attribute `index` (M_v or M_a) into rhs[r][column + c]: one vector load per
// entry from the evaluator's block copy when it has one, else gathered from each lane's row one
// entry of all lanes at a time (the transpose the other way round, one lane's 36 entries at a
// time, cost a fifth of the whole objective). The errors are local()'s.
template <int Cols>
[[gnu::always_inline]] inline void load_attribute(const QuantityBlock& q, int index, const char* name, const char* term,
                                                  Lanes (&rhs)[6][Cols], int column) {
  if (const double* lanes = q.attribute_lanes(index); lanes && q.attributes[index]->cols() == 36) {
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) rhs[r][column + c] = Lanes::load(lanes + (r * 6 + c) * kBlockLanes);
    }
    return;
  }
  const double* rows[kBlockLanes];
  for (int lane = 0; lane < kBlockLanes; ++lane) rows[lane] = lane_attribute(q, index, lane, name, term);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) rhs[r][column + c] = gather(rows, r * 6 + c);
  }
}

// The set of the lanes' row indices (each lane holds a small whole number) as bits: bit r is set
// when some lane holds r. One conversion, one shift and or_of_lanes(), where reading the lanes
// one by one cost a conversion and a shift per lane.
[[gnu::always_inline]] inline unsigned row_bits(const Lanes& row) {
  return static_cast<unsigned>(or_of_lanes((LaneBits{} + 1) << __builtin_convertvector(row.v, LaneBits)));
}

// Solves J X = B in place for every lane (B: 6 x Cols right-hand sides). \return per lane 1
// when every pivot was non-zero (the lane's J regular, as local() decides it), else 0.
// J is factored first (its row swaps, multipliers and inverse pivots kept), then each column of
// B is solved on its own: each column sees local()'s operations in local()'s order, and its six
// values stay in registers instead of the whole of B spilling during the factorization.
template <int Cols>
[[gnu::always_inline]] inline Lanes eliminate_lanes(Lanes (&a)[6][6], Lanes (&b)[6][Cols]) {
  const Lanes zero = Lanes::splat(0.0), one = Lanes::splat(1.0);
  Lanes regular = one;
  Lanes pivot_row[6], inverse_pivot[6], factor[6][6];
  unsigned swapped[6] = {};  // bit i of swapped[k]: row i is some lane's pivot at step k
    for (int k = 0; k < 6; ++k) {
    // The first row of largest |a(i, k)|, i >= k, per lane (local()'s strict comparison).
    Lanes best = abs(a[k][k]), row = Lanes::splat(k);
        for (int i = k + 1; i < 6; ++i) {
      const Lanes candidate = abs(a[i][k]);
      row = where_greater(candidate, best, Lanes::splat(i), row);
      best = max(candidate, best);
    }
    pivot_row[k] = row;
    regular = where_equal(best, zero, zero, regular);
    swapped[k] = row_bits(row);
    for (int i = k + 1; i < 6; ++i) {  // swap rows k and the pivot row, lane by lane
      if (!(swapped[k] >> i & 1u)) continue;  // most rows are no lane's pivot: skip their blends
      const Lanes here = Lanes::splat(i);
            for (int c = k; c < 6; ++c) {
        const Lanes t = a[k][c];
        a[k][c] = where_equal(row, here, a[i][c], t);
        a[i][c] = where_equal(row, here, t, a[i][c]);
      }
    }
    // A zero pivot's lane is abandoned (not regular); dividing by 1 there keeps it finite.
    inverse_pivot[k] = one / where_equal(a[k][k], zero, one, a[k][k]);
        for (int i = k + 1; i < 6; ++i) {
      factor[i][k] = a[i][k] * inverse_pivot[k];
            for (int c = k; c < 6; ++c) a[i][c] -= factor[i][k] * a[k][c];
    }
  }
  for (int j = 0; j < Cols; ++j) {
    Lanes x[6];
    #pragma GCC unroll 6
    for (int r = 0; r < 6; ++r) x[r] = b[r][j];
    #pragma GCC unroll 6
    for (int k = 0; k < 6; ++k) {
      #pragma GCC unroll 6
      for (int i = k + 1; i < 6; ++i) {
        if (!(swapped[k] >> i & 1u)) continue;
        const Lanes here = Lanes::splat(i), t = x[k];
        x[k] = where_equal(pivot_row[k], here, x[i], t);
        x[i] = where_equal(pivot_row[k], here, t, x[i]);
      }
      #pragma GCC unroll 6
      for (int i = k + 1; i < 6; ++i) x[i] -= factor[i][k] * x[k];
    }
    #pragma GCC unroll 6
    for (int k = 5; k >= 0; --k) {
      #pragma GCC unroll 6
      for (int c = k + 1; c < 6; ++c) x[k] -= a[k][c] * x[c];
      x[k] *= inverse_pivot[k];
    }
    #pragma GCC unroll 6
    for (int r = 0; r < 6; ++r) b[r][j] = x[r];
  }
  return regular;
}

// local()'s min(1, min_i limit_i / (max_j |M_ij| + |extra_i|)) per lane, 0 for a lane with a
// non-finite entry. `m(i, j)` gives entry (i, j) of the lane matrix.
template <typename Entry>
[[gnu::always_inline]] inline Lanes ratio_eta_lanes(const Entry& m, const double* limit, const Lanes* extra) {
  const Lanes zero = Lanes::splat(0.0), one = Lanes::splat(1.0);
  // 0 * x is 0 for finite x and NaN for an infinite or NaN x: one sum marks a lane with any
  // non-finite entry, without a comparison per entry.
  Lanes eta = one, poison = zero;
  for (int i = 0; i < 6; ++i) {
    Lanes need = abs(m(i, 0));
    poison += need * 0.0;
    for (int j = 1; j < 6; ++j) {
      const Lanes e = abs(m(i, j));
      poison += e * 0.0;
      need = max(e, need);
    }
    if (extra) need += abs(extra[i]);
    poison += need * 0.0;
    const Lanes bound = Lanes::splat(limit[i]);
    eta = where_greater(need * eta, bound, bound / where_equal(need, zero, one, need), eta);
  }
  return where_equal(poison, zero, eta, zero);
}

// out = H x per lane (H: the block's inertia, x: 6 x 6 lanes), summed over k in order.
template <typename Entry>
[[gnu::always_inline]] inline void inertia_times(const QuantityBlock& q, const Entry& x, Lanes (&out)[6][6]) {
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      Lanes sum = Lanes::load(q.inertia[r * 6]) * x(0, c);
      for (int j = 1; j < 6; ++j) sum += Lanes::load(q.inertia[r * 6 + j]) * x(j, c);
      out[r][c] = sum;
    }
  }
}

}  // namespace

// The velocity and acceleration terms of the block into out (local k onwards): M_v in columns
// 0..5 when the velocity term is selected, M_a in the next 6 when the acceleration term is.
template <int Cols>
[[gnu::always_inline]] inline void Coverage::velocity_acceleration(const QuantityBlock& q, const Lanes (&jacobian)[6][6],
                                                                  const Lanes* gravity, const Lanes& reachable,
                                                                  double* out, int& k) const {
  const Lanes zero = Lanes::splat(0.0), one = Lanes::splat(1.0);
  const int m_a_column = velocity_ ? 6 : 0;
  Lanes a[6][6], rhs[6][Cols];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) a[r][c] = jacobian[r][c];
  }
  if (velocity_) load_attribute(q, 0, "M_v", "velocity", rhs, 0);
  if (acceleration_) load_attribute(q, velocity_ ? 1 : 0, "M_a", "acceleration", rhs, m_a_column);
  const Lanes use = eliminate_lanes(a, rhs) * reachable;
  if (velocity_) {
    const auto velocity = [&](int i, int j) -> const Lanes& { return rhs[i][j]; };
    where_equal(use, one, ratio_eta_lanes(velocity, q.max_velocity, nullptr), zero).store(out + kBlockLanes * k++);
  }
  if (acceleration_) {
    Lanes torque[6][6];  // H J^-1 M_a
    inertia_times(q, [&](int j, int c) -> const Lanes& { return rhs[j][m_a_column + c]; }, torque);
    const auto entry = [&](int i, int j) -> const Lanes& { return torque[i][j]; };
    where_equal(use, one, ratio_eta_lanes(entry, q.max_torque, gravity), zero).store(out + kBlockLanes * k++);
  }
}

HAPSYN_MULTIVERSION_WIDE
void Coverage::local_block_impl(const QuantityBlock& q, double* out) const {
  const Lanes zero = Lanes::splat(0.0), one = Lanes::splat(1.0);
  Lanes reachable;  // 1 or 0
  for (int lane = 0; lane < kBlockLanes; ++lane) {
    reachable.v[lane] = q.lane_status(lane) == SampleStatus::kReachable ? 1.0 : 0.0;
  }
  one.store(out);
  reachable.store(out + kBlockLanes);
  if (!(velocity_ || acceleration_ || force_)) return;
  if (q.jacobian_rows != 6 || q.jacobian_cols != 6) {
    throw Error(kName, "the mechanism's Jacobian is " + std::to_string(q.jacobian_rows) + "x" +
                           std::to_string(q.jacobian_cols) + ": coverage needs a 6x6 (omega, v) Jacobian of a 6-joint arm");
  }
  if (!any_nonzero(reachable)) {  // every term is 0 for such lanes: a block without one skips them
    int terms = 2;
    for (const bool term : {velocity_, acceleration_, force_}) {
      if (term) zero.store(out + kBlockLanes * terms++);
    }
    return;
  }
  Lanes jacobian[6][6], gravity[6];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) jacobian[r][c] = Lanes::load(q.jacobian[r * 6 + c]);
    gravity[r] = (acceleration_ || force_) ? Lanes::load(q.gravity[r]) : zero;
  }
  int k = 2;
  // One elimination of J serves both terms ([M_v | M_a], as local() does it); a single term
  // eliminates its 6 columns only.
  if (velocity_ && acceleration_) {
    velocity_acceleration<12>(q, jacobian, gravity, reachable, out, k);
  } else if (velocity_ || acceleration_) {
    velocity_acceleration<6>(q, jacobian, gravity, reachable, out, k);
  }
  if (force_) {
    // C = J^T diag(m_max I, f_max I): entry (i, j) is J(j, i) scaled by column j's bound.
    Lanes c[6][6];
    for (int i = 0; i < 6; ++i) {
      for (int j = 0; j < 6; ++j) c[i][j] = jacobian[j][i] * (j < 3 ? options_.m_max : options_.f_max);
    }
    const auto entry = [&](int i, int j) -> const Lanes& { return c[i][j]; };
    where_equal(reachable, one, ratio_eta_lanes(entry, q.max_torque, gravity), zero).store(out + kBlockLanes * k++);
  }
}

void Coverage::local_block(const QuantityBlock& q, double* out) const { local_block_impl(q, out); }

namespace {
// x = J^-1 x, or H J^-1 x with `times_inertia`, for every lane.
HAPSYN_MULTIVERSION_WIDE
void solve_jacobian_lanes(const QuantityBlock& q, double (*x)[kBlockLanes], double* regular, bool times_inertia) {
  Lanes a[6][6], b[6][6];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      a[r][c] = Lanes::load(q.jacobian[r * 6 + c]);
      b[r][c] = Lanes::load(x[r * 6 + c]);
    }
  }
  eliminate_lanes(a, b).store(regular);
  if (times_inertia) {
    Lanes product[6][6];
    inertia_times(q, [&](int j, int c) -> const Lanes& { return b[j][c]; }, product);
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) b[r][c] = product[r][c];
    }
  }
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) b[r][c].store(x[r * 6 + c]);
  }
}
}  // namespace

void Coverage::solve_jacobian_block(const QuantityBlock& q, double (*x)[kBlockLanes], double* regular) {
  solve_jacobian_lanes(q, x, regular, false);
}

void Coverage::acceleration_torque_block(const QuantityBlock& q, double (*x)[kBlockLanes], double* regular) {
  solve_jacobian_lanes(q, x, regular, true);
}

}  // namespace hapsyn::plugins
