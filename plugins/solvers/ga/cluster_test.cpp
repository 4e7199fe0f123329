// k-means + average silhouette (cluster.hpp of the ga solver) on synthetic clustered data.
#include "cluster.hpp"

#include <gtest/gtest.h>

#include <random>
#include <set>

namespace {
// `per_cluster` points around each centre with Gaussian noise of `sigma`, clusters interleaved.
Eigen::MatrixXd blobs(const Eigen::MatrixXd& centres, int per_cluster, double sigma, std::uint64_t seed,
                      std::vector<int>* truth = nullptr) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  Eigen::MatrixXd points(centres.rows() * per_cluster, centres.cols());
  for (int i = 0; i < per_cluster; ++i) {
    for (Eigen::Index c = 0; c < centres.rows(); ++c) {
      const Eigen::Index row = i * centres.rows() + c;
      for (Eigen::Index d = 0; d < centres.cols(); ++d) points(row, d) = centres(c, d) + noise(rng);
      if (truth) truth->push_back(static_cast<int>(c));
    }
  }
  return points;
}

Eigen::MatrixXd three_centres() {
  Eigen::MatrixXd c(3, 5);  // link-length-like centres [m], ~60 mm apart
  c << 0.50, 0.45, 0.70, 0.55, 0.15,
       0.56, 0.40, 0.66, 0.60, 0.18,
       0.46, 0.50, 0.62, 0.50, 0.20;
  return c;
}
}  // namespace

TEST(Cluster, SilhouettePicksTheThreeSyntheticClusters) {
  std::vector<int> truth;
  const Eigen::MatrixXd points = blobs(three_centres(), 10, 0.004, 3, &truth);
  const hapsyn::plugins::ClusterAnalysis a = hapsyn::plugins::cluster_by_silhouette(points, 6, 1);
  ASSERT_EQ(a.best.k, 3);
  EXPECT_EQ(a.silhouettes.size(), 5u);  // k = 2..6
  EXPECT_GT(a.silhouette, 0.7);
  // The same partition as the truth (up to renumbering): labels agree pairwise.
  for (std::size_t i = 0; i < truth.size(); ++i) {
    for (std::size_t j = 0; j < truth.size(); ++j) {
      EXPECT_EQ(truth[i] == truth[j], a.best.labels[i] == a.best.labels[j]) << i << " " << j;
    }
  }
  EXPECT_EQ(a.sizes, (std::vector<int>{10, 10, 10}));
  // Intra deviation ~ sigma * E|N(0, I_5)| ~ 0.004 * 2.1; inter deviation ~ distance of centres to their mean.
  EXPECT_GT(a.intra_deviation, 0.004);
  EXPECT_LT(a.intra_deviation, 0.012);
  const Eigen::MatrixXd c = three_centres();
  double inter = 0.0;
  for (int k = 0; k < 3; ++k) inter += (c.row(k) - c.colwise().mean()).norm();
  EXPECT_NEAR(a.inter_deviation, inter / 3, 0.005);
}

TEST(Cluster, TwoWellSeparatedClustersBeatThree) {
  Eigen::MatrixXd centres(2, 2);
  centres << 0.0, 0.0, 1.0, 1.0;
  const hapsyn::plugins::ClusterAnalysis a = hapsyn::plugins::cluster_by_silhouette(blobs(centres, 15, 0.02, 5), 5, 2);
  EXPECT_EQ(a.best.k, 2);
  EXPECT_GT(a.silhouettes[0], a.silhouettes[1]);
}

TEST(Cluster, KMeansIsDeterministicUnderASeedAndLabelsByFirstAppearance) {
  const Eigen::MatrixXd points = blobs(three_centres(), 8, 0.01, 9);
  const hapsyn::plugins::KMeansResult a = hapsyn::plugins::kmeans(points, 3, 42);
  const hapsyn::plugins::KMeansResult b = hapsyn::plugins::kmeans(points, 3, 42);
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_TRUE(a.centroids == b.centroids);
  EXPECT_EQ(a.labels[0], 0);
  EXPECT_EQ(std::set<int>(a.labels.begin(), a.labels.end()).size(), 3u);
}

TEST(Cluster, SilhouetteOfAPerfectAndOfAWrongLabelling) {
  Eigen::MatrixXd points(4, 1);
  points << 0.0, 0.1, 10.0, 10.1;
  EXPECT_NEAR(hapsyn::plugins::average_silhouette(points, {0, 0, 1, 1}, 2), 1.0 - 0.1 / 10.0, 1e-3);
  EXPECT_LT(hapsyn::plugins::average_silhouette(points, {0, 1, 0, 1}, 2), 0.0);
  EXPECT_EQ(hapsyn::plugins::average_silhouette(points, {0, 0, 0, 0}, 1), 0.0);
}

TEST(Cluster, FewerThanThreePointsMakeOneCluster) {
  Eigen::MatrixXd points(2, 3);
  points << 0, 0, 0, 1, 1, 1;
  const hapsyn::plugins::ClusterAnalysis a = hapsyn::plugins::cluster_by_silhouette(points, 5, 1);
  EXPECT_EQ(a.best.k, 1);
  EXPECT_TRUE(a.silhouettes.empty());
  EXPECT_NEAR(a.intra_deviation, std::sqrt(3.0) / 2, 1e-12);
  EXPECT_NEAR(a.inter_deviation, 0.0, 1e-12);
}
