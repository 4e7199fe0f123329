#pragma once
/// \file
/// The options ga and nsga2 share, declared once: how a batch of designs uses the threads and
/// which design variables the sort repair orders. Solvers include it as "shared/batch_options.hpp".
#include <hapsyn/options.hpp>

namespace hapsyn::plugins {

/// Declares parallel_over, sample_chunks, sort_descending and sort_ascending for an options struct
/// O with members of those names (std::string, int, std::vector<std::string> twice).
template <class O>
void declare_batch_options(OptionDeclarations<O>& d) {
  d.add(&O::parallel_over, "parallel_over", "individuals",
        "How a batch of designs uses the threads: one design "
        "per thread, or each design split over the samples")
      .one_of({"individuals", "samples"});
  d.add(&O::sample_chunks, "sample_chunks", 16,
        "Fixed number of sample chunks when one design is split over the samples (results independent of the "
        "thread count)")
      .range(1, 4096);
  d.add(&O::sort_descending, "sort_descending", {},
        "Repair: design variables whose free components are sorted in descending order before evaluation "
        "(haptic6r: [\"s\"] for s_i >= s_{i+1})");
  d.add(&O::sort_ascending, "sort_ascending", {},
        "Repair: design variables whose free components are sorted in ascending order before evaluation");
}

}  // namespace hapsyn::plugins
