#pragma once
/// \file
/// The five-bar's block kernel (hapsyn/accel/sample_block.hpp): kBlockLanes samples per call, one per
/// SIMD lane, without trigonometric functions. The same model as FiveBarModel::solve (README,
/// "Conventions and equations"); its validity test works on the link vectors instead of the
/// joint angles, which is equivalent for every non-singular sample (KERNELS.md section 13.2).
#include <hapsyn/quantities.hpp>
#include <hapsyn/accel/sample_block.hpp>

namespace hapsyn::plugins {

/// What the kernel reads of one design (FiveBarModel fills it once per design).
struct FiveBarBlockDesign {
  double h0 = 0.0;                     ///< l0 / 2 [m]
  double l1 = 0.0, l2 = 0.0, r = 0.0;  ///< link lengths and placement [m]
  double singularity_tolerance = 0.0;  ///< smallest admissible |sin| of the transmission angles [-]
  double m2 = 0.0;                     ///< free bar mass [kg]
  double inertia_a = 0.0;              ///< actuated bar about its joint [kg m^2]
  double inertia_f = 0.0;              ///< free bar about its centre [kg m^2]
};

/// The instruction set the kernel runs with on this CPU (Highway's name: "AVX3", "AVX2", ...).
const char* fivebar_block_target();

/// Classifies the lanes of a block of scene samples (x[i], y[i]) [m] and fills, for the
/// reachable lanes, J, D and M as `needs` asks (2 x 2 each), bit for bit as FiveBarModel::solve.
/// Every lane is computed (lanes beyond the block's count carry copies of a valid sample).
/// Compiled with Highway for every instruction set it targets, dispatched at the first call to
/// the best the CPU has. No allocation, no throw.
void solve_fivebar_block(const FiveBarBlockDesign& design, const double* x, const double* y, Needs needs,
                         QuantityBlock& out);

}  // namespace hapsyn::plugins
