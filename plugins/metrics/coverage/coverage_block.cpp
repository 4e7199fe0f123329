// Coverage's block path (KERNELS.md section 14.3): local() for kBlockLanes samples at once, one
// sample per lane. The elimination of J with partial pivoting picks each lane's own pivot row
// and swaps rows by lane-wise selection, so every lane takes the pivots local() takes.
#include "coverage.hpp"

#include <hapsyn/error.hpp>
#include <hapsyn/accel/lanes.hpp>
#include <hapsyn/accel/vector_dispatch.hpp>

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
template <class L>
[[gnu::always_inline]] inline L gather(const double* const (&rows)[kBlockLanes], int e) {
  L r;
  for (int lane = 0; lane < kBlockLanes; ++lane) r.set(lane, rows[lane][e]);
  return r;
}

// The lanes' 6x6 attribute `index` (M_v or M_a) into rhs[r][column + c]: one vector load per
// entry from the evaluator's block copy when it has one, else gathered from each lane's row one
// entry of all lanes at a time (the transpose the other way round, one lane's 36 entries at a
// time, cost a fifth of the whole objective). The errors are local()'s.
template <class L, int Cols>
[[gnu::always_inline]] inline void load_attribute(const QuantityBlock& q, int index, const char* name, const char* term,
                                                  L (&rhs)[6][Cols], int column) {
  if (const double* lanes = q.attribute_lanes(index); lanes && q.attributes[index]->cols() == 36) {
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) rhs[r][column + c] = L::load(lanes + (r * 6 + c) * kBlockLanes);
    }
    return;
  }
  const double* rows[kBlockLanes];
  for (int lane = 0; lane < kBlockLanes; ++lane) rows[lane] = lane_attribute(q, index, lane, name, term);
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) rhs[r][column + c] = gather<L>(rows, r * 6 + c);
  }
}

// The set of the lanes' row indices (each lane holds a small whole number) as bits: bit r is set
// when some lane holds r.
template <class L>
[[gnu::always_inline]] inline unsigned row_bits(const L& row) {
  return static_cast<unsigned>(bits_of_small_integers(row));
}

// Solves J X = B in place for every lane (B: 6 x Cols right-hand sides). \return per lane 1
// when every pivot was non-zero (the lane's J regular, as local() decides it), else 0.
// J is factored first (its row swaps, multipliers and inverse pivots kept), then each column of
// B is solved on its own: each column sees local()'s operations in local()'s order, and its six
// values stay in registers instead of the whole of B spilling during the factorization.
template <class L, int Cols>
[[gnu::always_inline]] inline L eliminate_lanes(L (&a)[6][6], L (&b)[6][Cols]) {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  L regular = one;
  L pivot_row[6], inverse_pivot[6], factor[6][6];
  unsigned swapped[6] = {};  // bit i of swapped[k]: row i is some lane's pivot at step k
    for (int k = 0; k < 6; ++k) {
    // The first row of largest |a(i, k)|, i >= k, per lane (local()'s strict comparison).
    L best = abs(a[k][k]), row = L::splat(k);
        for (int i = k + 1; i < 6; ++i) {
      const L candidate = abs(a[i][k]);
      row = where_greater(candidate, best, L::splat(i), row);
      best = max(candidate, best);
    }
    pivot_row[k] = row;
    regular = where_equal(best, zero, zero, regular);
    swapped[k] = row_bits(row);
    for (int i = k + 1; i < 6; ++i) {  // swap rows k and the pivot row, lane by lane
      if (!(swapped[k] >> i & 1u)) continue;  // most rows are no lane's pivot: skip their blends
      const L here = L::splat(i);
            for (int c = k; c < 6; ++c) {
        const L t = a[k][c];
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
    L x[6];
    #pragma GCC unroll 6
    for (int r = 0; r < 6; ++r) x[r] = b[r][j];
    #pragma GCC unroll 6
    for (int k = 0; k < 6; ++k) {
      #pragma GCC unroll 6
      for (int i = k + 1; i < 6; ++i) {
        if (!(swapped[k] >> i & 1u)) continue;
        const L here = L::splat(i), t = x[k];
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
template <class L, typename Entry>
[[gnu::always_inline]] inline L ratio_eta_lanes(const Entry& m, const double* limit, const L* extra) {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  // 0 * x is 0 for finite x and NaN for an infinite or NaN x: one sum marks a lane with any
  // non-finite entry, without a comparison per entry.
  L eta = one, poison = zero;
  for (int i = 0; i < 6; ++i) {
    L need = abs(m(i, 0));
    poison += need * 0.0;
    for (int j = 1; j < 6; ++j) {
      const L e = abs(m(i, j));
      poison += e * 0.0;
      need = max(e, need);
    }
    if (extra) need += abs(extra[i]);
    poison += need * 0.0;
    const L bound = L::splat(limit[i]);
    eta = where_greater(need * eta, bound, bound / where_equal(need, zero, one, need), eta);
  }
  return where_equal(poison, zero, eta, zero);
}

// out = H x per lane (H: the block's inertia, x: 6 x 6 lanes), summed over k in order.
template <class L, typename Entry>
[[gnu::always_inline]] inline void inertia_times(const QuantityBlock& q, const Entry& x, L (&out)[6][6]) {
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      L sum = L::load(q.inertia[r * 6]) * x(0, c);
      for (int j = 1; j < 6; ++j) sum += L::load(q.inertia[r * 6 + j]) * x(j, c);
      out[r][c] = sum;
    }
  }
}

}  // namespace

// The velocity and acceleration terms of the block into out (local k onwards): M_v in columns
// 0..5 when the velocity term is selected, M_a in the next 6 when the acceleration term is.
template <int Cols, class L>
[[gnu::always_inline]] inline void Coverage::velocity_acceleration(const QuantityBlock& q, const L (&jacobian)[6][6],
                                                                  const L* gravity, const L& reachable,
                                                                  double* out, int& k) const {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  const int m_a_column = velocity_ ? 6 : 0;
  L a[6][6], rhs[6][Cols];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) a[r][c] = jacobian[r][c];
  }
  if (velocity_) load_attribute(q, 0, "M_v", "velocity", rhs, 0);
  if (acceleration_) load_attribute(q, velocity_ ? 1 : 0, "M_a", "acceleration", rhs, m_a_column);
  const L use = eliminate_lanes(a, rhs) * reachable;
  if (velocity_) {
    const auto velocity = [&](int i, int j) -> const L& { return rhs[i][j]; };
    where_equal(use, one, ratio_eta_lanes<L>(velocity, q.max_velocity, nullptr), zero).store(out + kBlockLanes * k++);
  }
  if (acceleration_) {
    L torque[6][6];  // H J^-1 M_a
    inertia_times(q, [&](int j, int c) -> const L& { return rhs[j][m_a_column + c]; }, torque);
    const auto entry = [&](int i, int j) -> const L& { return torque[i][j]; };
    where_equal(use, one, ratio_eta_lanes<L>(entry, q.max_torque, gravity), zero).store(out + kBlockLanes * k++);
  }
}

template <class L>
[[gnu::always_inline]] inline void Coverage::local_block_lanes(const QuantityBlock& q, double* out) const {
  const L zero = L::splat(0.0), one = L::splat(1.0);
  L reachable;  // 1 or 0
  for (int lane = 0; lane < kBlockLanes; ++lane) {
    reachable.set(lane, q.lane_status(lane) == SampleStatus::kReachable ? 1.0 : 0.0);
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
  L jacobian[6][6], gravity[6];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) jacobian[r][c] = L::load(q.jacobian[r * 6 + c]);
    gravity[r] = (acceleration_ || force_) ? L::load(q.gravity[r]) : zero;
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
    L c[6][6];
    for (int i = 0; i < 6; ++i) {
      for (int j = 0; j < 6; ++j) c[i][j] = jacobian[j][i] * (j < 3 ? options_.m_max : options_.f_max);
    }
    const auto entry = [&](int i, int j) -> const L& { return c[i][j]; };
    where_equal(reachable, one, ratio_eta_lanes<L>(entry, q.max_torque, gravity), zero).store(out + kBlockLanes * k++);
  }
}

void Coverage::local_block(const QuantityBlock& q, double* out) const {
  with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY { local_block_lanes<typename decltype(tag)::type>(q, out); });
}

namespace {
// x = J^-1 x, or H J^-1 x with `times_inertia`, for every lane.
template <class L>
[[gnu::always_inline]] inline void solve_jacobian_lanes(const QuantityBlock& q, double (*x)[kBlockLanes], double* regular, bool times_inertia) {
  L a[6][6], b[6][6];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      a[r][c] = L::load(q.jacobian[r * 6 + c]);
      b[r][c] = L::load(x[r * 6 + c]);
    }
  }
  eliminate_lanes(a, b).store(regular);
  if (times_inertia) {
    L product[6][6];
    inertia_times(q, [&](int j, int c) -> const L& { return b[j][c]; }, product);
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
  with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
    solve_jacobian_lanes<typename decltype(tag)::type>(q, x, regular, false);
  });
}

void Coverage::acceleration_torque_block(const QuantityBlock& q, double (*x)[kBlockLanes], double* regular) {
  with_vector_lanes([&](auto tag) HAPSYN_KERNEL_BODY {
    solve_jacobian_lanes<typename decltype(tag)::type>(q, x, regular, true);
  });
}

}  // namespace hapsyn::plugins
