#include "cluster.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <random>

namespace hapsyn::plugins {

namespace {

// Lloyd iterations from the given centroids; returns the inertia.
double lloyd(const Eigen::MatrixXd& points, Eigen::MatrixXd& centroids, std::vector<int>& labels, int max_iterations) {
  const Eigen::Index n = points.rows();
  const Eigen::Index k = centroids.rows();
  labels.assign(static_cast<std::size_t>(n), -1);
  double inertia = 0.0;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    bool changed = false;
    inertia = 0.0;
    for (Eigen::Index i = 0; i < n; ++i) {
      int nearest = 0;
      double best = std::numeric_limits<double>::infinity();
      for (Eigen::Index c = 0; c < k; ++c) {
        const double d = (points.row(i) - centroids.row(c)).squaredNorm();
        if (d < best) {
          best = d;
          nearest = static_cast<int>(c);
        }
      }
      inertia += best;
      if (labels[static_cast<std::size_t>(i)] != nearest) {
        labels[static_cast<std::size_t>(i)] = nearest;
        changed = true;
      }
    }
    if (!changed && iteration > 0) break;
    Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(k, points.cols());
    std::vector<int> counts(static_cast<std::size_t>(k), 0);
    for (Eigen::Index i = 0; i < n; ++i) {
      sums.row(labels[static_cast<std::size_t>(i)]) += points.row(i);
      ++counts[static_cast<std::size_t>(labels[static_cast<std::size_t>(i)])];
    }
    for (Eigen::Index c = 0; c < k; ++c) {
      if (counts[static_cast<std::size_t>(c)] > 0) centroids.row(c) = sums.row(c) / counts[static_cast<std::size_t>(c)];
    }
  }
  return inertia;
}

}  // namespace

KMeansResult kmeans(const Eigen::MatrixXd& points, int k, std::uint64_t seed, int restarts, int max_iterations) {
  const Eigen::Index n = points.rows();
  assert(k >= 1 && k <= n);
  std::mt19937_64 rng(seed);
  KMeansResult best;
  best.inertia = std::numeric_limits<double>::infinity();
  for (int start = 0; start < std::max(1, restarts); ++start) {
    // k-means++: the first centre uniformly, each next one with probability ~ squared distance.
    Eigen::MatrixXd centroids(k, points.cols());
    std::uniform_int_distribution<Eigen::Index> first(0, n - 1);
    centroids.row(0) = points.row(first(rng));
    std::vector<double> d2(static_cast<std::size_t>(n));
    for (int c = 1; c < k; ++c) {
      double total = 0.0;
      for (Eigen::Index i = 0; i < n; ++i) {
        double m = std::numeric_limits<double>::infinity();
        for (int j = 0; j < c; ++j) m = std::min(m, (points.row(i) - centroids.row(j)).squaredNorm());
        d2[static_cast<std::size_t>(i)] = m;
        total += m;
      }
      Eigen::Index pick = 0;
      if (total > 0.0) {
        double r = std::uniform_real_distribution<double>(0.0, total)(rng);
        for (pick = 0; pick < n - 1; ++pick) {
          r -= d2[static_cast<std::size_t>(pick)];
          if (r < 0.0) break;
        }
      } else {
        pick = first(rng);
      }
      centroids.row(c) = points.row(pick);
    }
    std::vector<int> labels;
    const double inertia = lloyd(points, centroids, labels, max_iterations);
    if (inertia < best.inertia - 1e-12 * std::max(1.0, inertia)) {
      best.inertia = inertia;
      best.centroids = centroids;
      best.labels = labels;
    }
  }
  // Renumber by first appearance (and drop empty clusters' rows consistently).
  std::vector<int> map(static_cast<std::size_t>(k), -1);
  int next = 0;
  for (int& label : best.labels) {
    if (map[static_cast<std::size_t>(label)] < 0) map[static_cast<std::size_t>(label)] = next++;
    label = map[static_cast<std::size_t>(label)];
  }
  Eigen::MatrixXd ordered(next, points.cols());
  for (int c = 0; c < k; ++c) {
    if (map[static_cast<std::size_t>(c)] >= 0) ordered.row(map[static_cast<std::size_t>(c)]) = best.centroids.row(c);
  }
  best.centroids = ordered;
  best.k = next;
  return best;
}

double average_silhouette(const Eigen::MatrixXd& points, const std::vector<int>& labels, int k) {
  const Eigen::Index n = points.rows();
  if (k < 2 || n < 2) return 0.0;
  std::vector<int> sizes(static_cast<std::size_t>(k), 0);
  for (int l : labels) ++sizes[static_cast<std::size_t>(l)];
  double total = 0.0;
  std::vector<double> sum(static_cast<std::size_t>(k));
  for (Eigen::Index i = 0; i < n; ++i) {
    std::fill(sum.begin(), sum.end(), 0.0);
    for (Eigen::Index j = 0; j < n; ++j) {
      if (j != i) sum[static_cast<std::size_t>(labels[static_cast<std::size_t>(j)])] += (points.row(i) - points.row(j)).norm();
    }
    const int own = labels[static_cast<std::size_t>(i)];
    if (sizes[static_cast<std::size_t>(own)] <= 1) continue;  // a singleton scores 0
    const double a = sum[static_cast<std::size_t>(own)] / (sizes[static_cast<std::size_t>(own)] - 1);
    double b = std::numeric_limits<double>::infinity();
    for (int c = 0; c < k; ++c) {
      if (c != own && sizes[static_cast<std::size_t>(c)] > 0) b = std::min(b, sum[static_cast<std::size_t>(c)] / sizes[static_cast<std::size_t>(c)]);
    }
    const double denominator = std::max(a, b);
    if (denominator > 0.0 && std::isfinite(b)) total += (b - a) / denominator;
  }
  return total / static_cast<double>(n);
}

ClusterAnalysis cluster_by_silhouette(const Eigen::MatrixXd& points, int max_k, std::uint64_t seed) {
  ClusterAnalysis out;
  const int n = static_cast<int>(points.rows());
  const int top = std::min(max_k, n - 1);
  if (n == 0) return out;
  if (top < 2) {
    out.best = kmeans(points, 1, seed);
  } else {
    double best = -std::numeric_limits<double>::infinity();
    for (int k = 2; k <= top; ++k) {
      KMeansResult r = kmeans(points, k, seed + static_cast<std::uint64_t>(k));
      const double s = average_silhouette(points, r.labels, r.k);
      out.silhouettes.push_back(s);
      if (s > best + 1e-12) {
        best = s;
        out.best = std::move(r);
        out.silhouette = s;
      }
    }
  }
  const int k = out.best.k;
  out.sizes.assign(static_cast<std::size_t>(k), 0);
  out.cluster_intra_distance.assign(static_cast<std::size_t>(k), 0.0);
  for (int i = 0; i < n; ++i) {
    const int c = out.best.labels[static_cast<std::size_t>(i)];
    const double d = (points.row(i) - out.best.centroids.row(c)).norm();
    out.cluster_intra_distance[static_cast<std::size_t>(c)] += d;
    out.intra_deviation += d;
    ++out.sizes[static_cast<std::size_t>(c)];
  }
  for (int c = 0; c < k; ++c) out.cluster_intra_distance[static_cast<std::size_t>(c)] /= out.sizes[static_cast<std::size_t>(c)];
  out.intra_deviation /= n;
  const Eigen::RowVectorXd mean = points.colwise().mean();
  for (int c = 0; c < k; ++c) out.inter_deviation += (out.best.centroids.row(c) - mean).norm();
  out.inter_deviation /= k;
  return out;
}

}  // namespace hapsyn::plugins
