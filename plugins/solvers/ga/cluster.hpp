#pragma once
/// \file
/// k-means clustering with the number of clusters chosen by the average silhouette: the
/// analysis Fennel et al. (2022, section VII) apply to the optima of independent GA runs.
///
/// Points are the rows of an n x d matrix (e.g. the link lengths of each run's optimum, in m).
/// Everything is deterministic under a seed (k-means++ initialisation drawn from it).
#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace hapsyn::plugins {

/// One k-means clustering.
struct KMeansResult {
  int k = 0;
  std::vector<int> labels;     ///< cluster of each point, 0..k-1, ordered by first appearance
  Eigen::MatrixXd centroids;   ///< k x d
  double inertia = 0.0;        ///< sum of squared distances of the points to their centroid
};

/// Lloyd's k-means from k-means++ seeds, the best (lowest inertia) of `restarts` starts.
/// Labels are renumbered by first appearance so that equal clusterings compare equal.
/// \pre 1 <= k <= points.rows()
KMeansResult kmeans(const Eigen::MatrixXd& points, int k, std::uint64_t seed, int restarts = 10,
                    int max_iterations = 300);

/// Average silhouette of a labelling: mean over the points of (b - a) / max(a, b), with a the
/// mean distance to the other points of the own cluster and b the smallest mean distance to
/// another cluster (a point alone in its cluster scores 0). In [-1, 1]; 0 when k < 2.
double average_silhouette(const Eigen::MatrixXd& points, const std::vector<int>& labels, int k);

/// The clustering chosen by the average silhouette among k = 2..max_k, with the deviations
/// Fennel et al. report.
struct ClusterAnalysis {
  KMeansResult best;                ///< the chosen clustering (k = 1 when fewer than 3 points)
  std::vector<double> silhouettes;  ///< average silhouette for k = 2, 3, ..., max_k
  double silhouette = 0.0;          ///< of the chosen k
  /// Per cluster, the mean Euclidean distance of its points to its centroid.
  std::vector<double> cluster_intra_distance;
  /// Intra-cluster deviation: mean over all points of the distance to their own centroid.
  double intra_deviation = 0.0;
  /// Inter-cluster deviation: mean over the clusters of the distance of the centroid to the
  /// overall mean of the points.
  double inter_deviation = 0.0;
  /// Per cluster, the number of points.
  std::vector<int> sizes;
};

/// Clusters the points with k-means for k = 2..min(max_k, n - 1) and keeps the k with the highest
/// average silhouette (ties: the smaller k). With fewer than 3 points, or max_k < 2, one cluster.
ClusterAnalysis cluster_by_silhouette(const Eigen::MatrixXd& points, int max_k, std::uint64_t seed);

}  // namespace hapsyn::plugins
