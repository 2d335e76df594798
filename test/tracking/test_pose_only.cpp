// Indirect step of the hybrid tracker: reprojection Jacobian against numeric differences, robust pose-only
// optimisation recovering a perturbed pose from noisy matches with outliers, and the utility weight K (paper eq. 4).
#include "tracking/PoseOnlyOptimizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace
{
using hslam::PinholeIntrinsics;
using hslam::ReprojectionObservation;
using hslam::SE3d;

const PinholeIntrinsics kK{500., 500., 319.5, 239.5};

SE3d poseFrom(const Eigen::Vector3d &rotationVector, const Eigen::Vector3d &t)
{
  Eigen::Matrix<double, 6, 1> xi;
  xi << Eigen::Vector3d::Zero(), rotationVector;
  const SE3d R = SE3d::exp(xi);
  return SE3d(R.unitQuaternion(), t);
}

double rotationErrorDeg(const SE3d &a, const SE3d &b)
{
  return (a.inverse() * b).log().tail<3>().norm() * 180. / M_PI;
}

// Points 2-6 m in front of the true camera, inside the image; a fraction of the matches replaced by random pixels.
std::vector<ReprojectionObservation> makeScene(const SE3d &cTw, int count, double noisePx, double outlierFraction,
                                               std::vector<bool> &isOutlier, std::mt19937 &rng)
{
  std::uniform_real_distribution<double> u(0., 640.), v(0., 480.), depth(2., 6.), unit(0., 1.);
  std::normal_distribution<double> noise(0., noisePx);
  const SE3d wTc = cTw.inverse();
  std::vector<ReprojectionObservation> out;
  isOutlier.clear();
  for (int i = 0; i < count; ++i) {
    const double z = depth(rng), pu = u(rng), pv = v(rng);
    const Eigen::Vector3d cX((pu - kK.cx) / kK.fx * z, (pv - kK.cy) / kK.fy * z, z);
    ReprojectionObservation obs;
    obs.wX = wTc * cX;
    const bool outlier = unit(rng) < outlierFraction;
    obs.uv = outlier ? Eigen::Vector2d(u(rng), v(rng)) : Eigen::Vector2d(pu + noise(rng), pv + noise(rng));
    obs.sigma2 = 1.;
    out.push_back(obs);
    isOutlier.push_back(outlier);
  }
  return out;
}

TEST(PoseOnly, ReprojectionJacobianMatchesNumericDifferences)
{
  const SE3d cTw = poseFrom(Eigen::Vector3d(0.1, -0.2, 0.05), Eigen::Vector3d(0.3, -0.1, 0.2));
  ReprojectionObservation obs;
  obs.wX = Eigen::Vector3d(0.4, -0.3, 3.5);
  obs.uv = Eigen::Vector2d(300., 250.);
  Eigen::Vector2d r0;
  Eigen::Matrix<double, 2, 6> J;
  ASSERT_TRUE(hslam::reprojectionResidual(cTw, obs, kK, 1e-6, r0, &J));
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
    d[k] = h;
    Eigen::Vector2d rp, rm;
    ASSERT_TRUE(hslam::reprojectionResidual(SE3d::exp(d) * cTw, obs, kK, 1e-6, rp));
    ASSERT_TRUE(hslam::reprojectionResidual(SE3d::exp(-d) * cTw, obs, kK, 1e-6, rm));
    const Eigen::Vector2d numeric = (rp - rm) / (2. * h);
    EXPECT_LT((numeric - J.col(k)).norm(), 1e-5 * (1. + numeric.norm())) << "column " << k;
  }
  obs.wX = cTw.inverse() * Eigen::Vector3d(0.1, 0.1, -1.); // behind the camera
  EXPECT_FALSE(hslam::reprojectionResidual(cTw, obs, kK, 1e-6, r0));
}

TEST(PoseOnly, RecoversAPerturbedPoseAndFlagsOutliers)
{
  std::mt19937 rng(7);
  const SE3d truth = poseFrom(Eigen::Vector3d(0.05, 0.3, -0.1), Eigen::Vector3d(0.2, -0.05, 0.4));
  std::vector<bool> isOutlier;
  const std::vector<ReprojectionObservation> obs = makeScene(truth, 300, 0.7, 0.25, isOutlier, rng);
  // 5 cm and about 3 degrees away: a constant-velocity prediction after a jerk.
  const SE3d start = poseFrom(Eigen::Vector3d(0.03, -0.03, 0.02), Eigen::Vector3d(0.03, -0.02, 0.03)) * truth;
  const hslam::PoseOnlyResult result = hslam::optimizePoseOnly(start, obs, kK);

  EXPECT_LT((result.cTw.translation() - truth.translation()).norm(), 0.005);
  EXPECT_LT(rotationErrorDeg(result.cTw, truth), 0.05);
  int outliers = 0, outliersFlagged = 0, inliersKept = 0;
  for (std::size_t i = 0; i < obs.size(); ++i) {
    outliers += isOutlier[i] ? 1 : 0;
    outliersFlagged += (isOutlier[i] && !result.inlier[i]) ? 1 : 0;
    inliersKept += (!isOutlier[i] && result.inlier[i]) ? 1 : 0;
  }
  const int inliers = static_cast<int>(obs.size()) - outliers;
  EXPECT_GE(outliersFlagged, outliers * 95 / 100); // a random pixel may fall within 2.4 px of the truth
  EXPECT_GE(inliersKept, inliers * 93 / 100);      // chi2 95 %: about 5 % of true matches are rejected
  EXPECT_LT(result.inlierRmsePx, 1.2);
  EXPECT_EQ(result.inliers, static_cast<int>(std::count(result.inlier.begin(), result.inlier.end(), true)));
}

TEST(PoseOnly, TooFewMatchesLeaveThePoseUnchanged)
{
  const SE3d start = poseFrom(Eigen::Vector3d(0.1, 0., 0.), Eigen::Vector3d(1., 2., 3.));
  std::vector<ReprojectionObservation> obs(2);
  const hslam::PoseOnlyResult result = hslam::optimizePoseOnly(start, obs, kK);
  EXPECT_EQ(result.inliers, 0);
  EXPECT_LT((result.cTw.translation() - start.translation()).norm(), 1e-15);
}

TEST(PoseOnly, UtilityWeightOfPaperEquation4)
{
  // K = 5 e^(-2 l) / (1 + e^((30 - N_g) / 4)).
  EXPECT_NEAR(hslam::geometricWeight(0, 30), 2.5, 1e-12);
  EXPECT_NEAR(hslam::geometricWeight(1, 30), 2.5 * std::exp(-2.), 1e-12);
  EXPECT_NEAR(hslam::geometricWeight(0, 0), 5. / (1. + std::exp(7.5)), 1e-12);
  EXPECT_NEAR(hslam::geometricWeight(0, 200), 5., 1e-6);
  // Fewer matches, or a later (finer) stage: less geometry.
  EXPECT_LT(hslam::geometricWeight(0, 20), hslam::geometricWeight(0, 40));
  EXPECT_LT(hslam::geometricWeight(2, 100), hslam::geometricWeight(1, 100));
}
} // namespace
