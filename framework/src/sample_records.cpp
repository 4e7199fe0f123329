// record_samples: every sample of one design, with its status and local values, in one pass.
#include <hapsyn/internal/maps.hpp>
#include <hapsyn/internal/solve_recording.hpp>
#include <hapsyn/parallel.hpp>

#include <algorithm>
#include <exception>
#include <memory>
#include <numeric>

namespace hapsyn {

namespace {

// The samples are split into contiguous pieces, a few per thread so that dynamic scheduling evens
// out samples of unequal cost, none shorter than kMinPiece: each piece builds the model once.
constexpr long long kPiecesPerThread = 8;
constexpr long long kMinPiece = 256;

long long piece_count(long long samples, int threads) {
  if (threads <= 1) return 1;
  return std::clamp(samples / kMinPiece, 1LL, kPiecesPerThread * threads);
}

// Samples [first, last) into `records`: one evaluation of the piece with the recording callback.
// An evaluation that stops at a sample (kSampleFailed: a worst-case metric met a sample the
// mechanism cannot serve) records that sample's status and resumes after it, so every sample is
// solved once and gets the status evaluating it alone would give; a violated design constraint
// is every sample's status, as it is for each sample alone.
void record_piece(const Problem& problem, const double* free_design, long long first, long long last,
                  const SampleCallback& record, const UnreachedSample& unreached, Problem::EvalScratch& scratch) {
  std::vector<int> subset(static_cast<std::size_t>(last - first));
  std::iota(subset.begin(), subset.end(), static_cast<int>(first));
  EvalOptions options;
  options.subset = &subset;
  options.on_sample = &record;
  while (!subset.empty()) {
    const Evaluation& e = problem.evaluate(free_design, scratch, options);
    if (e.status == EvalStatus::kSampleFailed) {
      unreached(e.failed_sample, to_string(e.failed_status));
      subset.erase(subset.begin(), std::find(subset.begin(), subset.end(), e.failed_sample) + 1);
      continue;
    }
    if (e.status == EvalStatus::kConstraintViolated) {
      for (const int sample : subset) unreached(sample, to_string(e.status));
    }
    return;  // kFeasible (kPruned needs pruning options, which are not set)
  }
}

}  // namespace

void evaluate_each_sample(const Problem& problem, const Eigen::VectorXd& full, int threads, const SampleCallback& record,
                          const UnreachedSample& unreached) {
  const long long n = problem.samples().size();
  Eigen::VectorXd free_design(static_cast<Eigen::Index>(problem.dimension()));
  for (std::size_t k = 0; k < problem.dimension(); ++k) {
    free_design[static_cast<Eigen::Index>(k)] = full[problem.design_space().free_indices()[k]];
  }
  const long long pieces = piece_count(n, threads);
  std::vector<std::unique_ptr<Problem::EvalScratch>> scratch(static_cast<std::size_t>(std::max(1, threads)));
  // A piece stops at its first error; the error of the lowest piece is rethrown, which is the
  // lowest-numbered sample's, whatever the thread count (as evaluating sample by sample).
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(pieces));
  parallel_for_dynamic(pieces, std::max(1, threads), 1, [&](long long p, int t) {
    auto& ws = scratch[static_cast<std::size_t>(t)];
    if (!ws) ws = problem.make_eval_scratch();  // made by the thread that uses it
    try {
      record_piece(problem, free_design.data(), n * p / pieces, n * (p + 1) / pieces, record, unreached, *ws);
    } catch (...) {
      errors[static_cast<std::size_t>(p)] = std::current_exception();
    }
  });
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

SampleRecords record_samples(const Problem& problem, const Eigen::VectorXd& full, int threads) {
  SampleRecords records = blank_records(problem);
  // Both are called on the pieces' threads, each for its own sample only.
  evaluate_each_sample(problem, full, threads, record_into(records), [&records](int sample, const std::string& status) {
    records.status[static_cast<std::size_t>(sample)] = status;
  });
  return records;
}

}  // namespace hapsyn
