// Evaluation maths on synthetic data with exact answers: association, Umeyama, ATE, RPE, TUM-mono e_align.
#include "HSlamTestData.h"

#include "eval/TrajectoryAlignment.h"
#include "eval/TrajectoryAssociation.h"
#include "eval/TrajectoryMetrics.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

namespace
{
using hslam::AlignmentMode;
using hslam::StampedPose;

Eigen::Matrix3d rotation(double angle, const Eigen::Vector3d &axis)
{
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

std::vector<Eigen::Vector3d> randomPoints(size_t n, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> uniform(-5., 5.);
  std::vector<Eigen::Vector3d> p(n);
  for (Eigen::Vector3d &x : p) {
    x = Eigen::Vector3d(uniform(rng), uniform(rng), uniform(rng));
  }
  return p;
}
} // namespace

TEST(TrajectoryAssociation, NearestWithinMaxDtOneToOne)
{
  // Ground truth at 100 Hz; estimates at irregular times, one outside any window, two competing for one stamp.
  std::vector<double> gt;
  for (int i = 0; i < 100; ++i) {
    gt.push_back(10. + 0.01 * i);
  }
  const std::vector<double> est = {10.0031, 10.5049, 10.5051, 20.0, 9.999};
  const auto matches = hslam::associateTimestamps(est, gt, 0.004);
  // Within 4 ms: 10.0031 and 9.999 both want 10.00; 9.999 is closer (1 ms) and wins, 10.0031 has nothing else
  // within 4 ms (10.01 is 6.9 ms away). 10.5049 and 10.5051 are 4.9 ms from their neighbours: unmatched; 20.0 too.
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].first, 4u);
  EXPECT_EQ(matches[0].second, 0u);

  const auto wide = hslam::associateTimestamps(est, gt, 0.0075);
  // Now: 9.999->10.00, 10.0031->10.01 (0.0069), 10.5049->10.50, 10.5051->10.51, 20.0 unmatched. Sorted by time.
  ASSERT_EQ(wide.size(), 4u);
  EXPECT_EQ(wide[0], std::make_pair(size_t(4), size_t(0)));
  EXPECT_EQ(wide[1], std::make_pair(size_t(0), size_t(1)));
  EXPECT_EQ(wide[2], std::make_pair(size_t(1), size_t(50)));
  EXPECT_EQ(wide[3], std::make_pair(size_t(2), size_t(51)));
}

TEST(TrajectoryAssociation, ScalesToLargeInputs)
{
  // 200 Hz ground truth over one hour and a 20 Hz estimate: a quadratic scan would take seconds here.
  std::vector<double> gt, est;
  for (int i = 0; i < 720000; ++i) {
    gt.push_back(0.005 * i);
  }
  for (int i = 0; i < 72000; ++i) {
    est.push_back(0.05 * i + 0.001);
  }
  const auto matches = hslam::associateTimestamps(est, gt, 0.02);
  ASSERT_EQ(matches.size(), est.size());
  for (size_t k = 0; k < matches.size(); k += 997) {
    EXPECT_EQ(matches[k].second, 10 * matches[k].first);
  }
}

TEST(TrajectoryAlignment, UmeyamaRecoversExactSim3)
{
  const std::vector<Eigen::Vector3d> source = randomPoints(50, 7);
  hslam::SimilarityTransform truth;
  truth.scale = 2.37;
  truth.R = rotation(1.1, Eigen::Vector3d(0.3, -0.5, 0.8));
  truth.t = Eigen::Vector3d(4., -2., 0.5);
  std::vector<Eigen::Vector3d> target;
  for (const Eigen::Vector3d &x : source) {
    target.push_back(truth.apply(x));
  }
  const hslam::SimilarityTransform found = hslam::alignUmeyama(source, target, AlignmentMode::sim3);
  EXPECT_NEAR(found.scale, truth.scale, 1e-9);
  EXPECT_LT((found.R - truth.R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((found.t - truth.t).cwiseAbs().maxCoeff(), 1e-9);

  // SE(3) on scale-free data recovers the rigid part, and "none" is the identity.
  std::vector<Eigen::Vector3d> rigidTarget;
  for (const Eigen::Vector3d &x : source) {
    rigidTarget.push_back(truth.R * x + truth.t);
  }
  const hslam::SimilarityTransform rigid = hslam::alignUmeyama(source, rigidTarget, AlignmentMode::se3);
  EXPECT_DOUBLE_EQ(rigid.scale, 1.);
  EXPECT_LT((rigid.R - truth.R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((rigid.t - truth.t).cwiseAbs().maxCoeff(), 1e-9);
  const hslam::SimilarityTransform none = hslam::alignUmeyama(source, target, AlignmentMode::none);
  EXPECT_TRUE(none.R.isIdentity(0.));
  EXPECT_DOUBLE_EQ(none.t.norm(), 0.);
}

TEST(TrajectoryAlignment, ReflectionGuardAndErrors)
{
  // Planar points: the cross-covariance has rank 2 and det(U)det(V) may be -1; the result must still be a rotation.
  std::vector<Eigen::Vector3d> source, target;
  const Eigen::Matrix3d R = rotation(-2.5, Eigen::Vector3d(1., 1., 0.));
  for (int i = 0; i < 20; ++i) {
    const Eigen::Vector3d x(std::cos(0.3 * i) * i, std::sin(0.3 * i), 0.);
    source.push_back(x);
    target.push_back(R * x);
  }
  const hslam::SimilarityTransform found = hslam::alignUmeyama(source, target, AlignmentMode::se3);
  EXPECT_NEAR(found.R.determinant(), 1., 1e-12);
  EXPECT_LT((found.R - R).cwiseAbs().maxCoeff(), 1e-9);

  EXPECT_THROW(hslam::alignUmeyama({source[0], source[1]}, {target[0], target[1]}, AlignmentMode::se3),
               vpHSlamException);
  EXPECT_THROW(hslam::alignUmeyama(source, {target[0]}, AlignmentMode::sim3), vpHSlamException);
}

TEST(TrajectoryMetrics, StatisticsOfKnownList)
{
  const hslam::ErrorStatistics s = hslam::computeErrorStatistics({3., 1., 4., 1., 5., 9.});
  EXPECT_EQ(s.count, 6u);
  EXPECT_DOUBLE_EQ(s.mean, 23. / 6.);
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(133. / 6.));
  EXPECT_DOUBLE_EQ(s.median, 3.5);
  EXPECT_DOUBLE_EQ(s.min, 1.);
  EXPECT_DOUBLE_EQ(s.max, 9.);
  EXPECT_NEAR(s.std, std::sqrt(133. / 6. - (23. / 6.) * (23. / 6.)), 1e-12);
}

TEST(TrajectoryMetrics, AteOfSimilarityTransformedTrajectoryIsZeroAndScaleRecovered)
{
  const std::vector<Eigen::Vector3d> p = randomPoints(40, 3);
  std::vector<StampedPose> gt, est;
  hslam::SimilarityTransform gMe;
  gMe.scale = 0.5;
  gMe.R = rotation(0.4, Eigen::Vector3d(0., 0., 1.));
  gMe.t = Eigen::Vector3d(1., 2., 3.);
  for (size_t i = 0; i < p.size(); ++i) {
    StampedPose e;
    e.timestamp = 0.1 * i;
    e.wtc = p[i];
    est.push_back(e);
    StampedPose g = e;
    g.wtc = gMe.apply(p[i]);
    // Known displacement on one pose: ATE max sees it.
    if (i == 10) {
      g.wtc += Eigen::Vector3d(0., 0., 1e-3);
    }
    gt.push_back(g);
  }
  const hslam::AteResult sim3 = hslam::computeAte(gt, est, AlignmentMode::sim3);
  EXPECT_NEAR(sim3.gtTest.scale, 0.5, 1e-4);
  EXPECT_LT(sim3.error.rmse, 2e-4);
  EXPECT_NEAR(sim3.error.max, 1e-3, 1e-4);
  const hslam::AteResult se3 = hslam::computeAte(gt, est, AlignmentMode::se3);
  EXPECT_GT(se3.error.rmse, 1.); // half scale: metres of error without Sim(3)
}

TEST(TrajectoryMetrics, RpeMeasuresConstantDrift)
{
  // Screw motion along z: per frame the ground truth turns a = 0.05 rad about z and advances v = 0.1 m along z.
  // The estimate turns a + w and advances v + d (w = 0.002 rad, d = 0.01 m per frame). Rotation axis and
  // translations are parallel, so over n frames E = (Rz(n w), n d) exactly: errors n |d| and n w.
  const double a = 0.05, w = 0.002, v = 0.1, d = 0.01, dt = 0.1;
  std::vector<StampedPose> gt, est;
  for (int k = 0; k < 60; ++k) {
    StampedPose g;
    g.timestamp = dt * k;
    g.wRc = rotation(k * a, Eigen::Vector3d::UnitZ());
    g.wtc = Eigen::Vector3d(0., 0., k * v);
    gt.push_back(g);
    StampedPose e = g;
    e.wRc = rotation(k * (a + w), Eigen::Vector3d::UnitZ());
    e.wtc = Eigen::Vector3d(0., 0., k * (v + d));
    est.push_back(e);
  }
  const int n = 5;
  const hslam::RpeResult byTime = hslam::computeRpe(gt, est, n * dt, false, 1.);
  EXPECT_EQ(byTime.translation.count, 60u - n);
  EXPECT_NEAR(byTime.translation.rmse, n * d, 1e-12);
  EXPECT_NEAR(byTime.translation.max - byTime.translation.min, 0., 1e-12);
  EXPECT_NEAR(byTime.rotationDeg.rmse, n * w * 180. / M_PI, 1e-9);

  const hslam::RpeResult byDistance = hslam::computeRpe(gt, est, n * v, true, 1.);
  EXPECT_EQ(byDistance.translation.count, 60u - n);
  EXPECT_NEAR(byDistance.translation.rmse, n * d, 1e-12);

  // Scaling the estimate by v / (v + d) removes the translation drift.
  const hslam::RpeResult scaled = hslam::computeRpe(gt, est, n * dt, false, v / (v + d));
  EXPECT_LT(scaled.translation.rmse, 1e-12);
}

TEST(TrajectoryMetrics, MonoAlignmentErrorOfScaleDrift)
{
  // A loop of radius 2 m over 60 s (1 Hz ground truth); the estimate's scale grows linearly from 1 to 1.5 along
  // the loop. Without drift e_align would be 0; with drift it must exceed the start/end segment errors.
  std::vector<StampedPose> gt, est, noDrift;
  for (int k = 0; k <= 60; ++k) {
    const double theta = 2. * M_PI * k / 60.;
    StampedPose g;
    g.timestamp = k;
    g.wtc = Eigen::Vector3d(2. * std::cos(theta), 2. * std::sin(theta), 0.1 * std::sin(3. * theta));
    gt.push_back(g);
    noDrift.push_back(g);
    StampedPose e = g;
    e.wtc *= 1. + 0.5 * k / 60.;
    est.push_back(e);
  }
  const hslam::MonoAlignmentResult exact = hslam::computeMonoAlignmentError(gt, noDrift, noDrift, 10.);
  EXPECT_LT(exact.alignmentError, 1e-9);
  EXPECT_NEAR(exact.scaleDrift, 1., 1e-9);
  EXPECT_EQ(exact.startCount, 11u);
  EXPECT_EQ(exact.endCount, 11u);

  const hslam::MonoAlignmentResult drift = hslam::computeMonoAlignmentError(gt, est, est, 10.);
  // Start segment scale about 1/1.04, end segment about 1/1.46: ratio about 1.4.
  EXPECT_GT(drift.scaleDrift, 1.3);
  EXPECT_LT(drift.scaleDrift, 1.5);
  EXPECT_GT(drift.alignmentError, 0.3);
  EXPECT_THROW(hslam::computeMonoAlignmentError(gt, est, est, 1.), vpHSlamException);
}

TEST(TrajectoryEvaluator, PublicApiOnSyntheticTrajectory)
{
  vpHSlamTrajectory gt, est;
  for (int k = 0; k < 100; ++k) {
    const double t = 0.05 * k;
    vpHomogeneousMatrix wMc(std::cos(t), std::sin(t), 0.2 * t, 0., 0.1 * t, t);
    gt.add(t, wMc);
    // Estimate: a different world frame, scale 3, stamps 5 ms late.
    vpHomogeneousMatrix eMw(1., -2., 0.5, 0.3, 0.2, 0.1);
    vpHomogeneousMatrix eMc = eMw * wMc;
    eMc[0][3] *= 3.;
    eMc[1][3] *= 3.;
    eMc[2][3] *= 3.;
    est.add(t + 0.005, eMc);
  }
  EXPECT_THROW(vpHSlamTrajectoryEvaluator(gt, est, -1.), vpHSlamException);
  const vpHSlamTrajectoryEvaluator none(gt, est, 0.001);
  EXPECT_EQ(none.getMatchedCount(), 0u);
  EXPECT_THROW(none.computeAte(), vpHSlamException);

  const vpHSlamTrajectoryEvaluator evaluator(gt, est, 0.02);
  EXPECT_EQ(evaluator.getMatchedCount(), 100u);
  const vpHSlamTrajectoryEvaluator::AteResult ate = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSim3);
  EXPECT_LT(ate.error.rmse, 1e-9);
  EXPECT_NEAR(ate.scale, 1. / 3., 1e-9);
  const vpHSlamTrajectoryEvaluator::RpeResult rpe = evaluator.computeRpe(0.5);
  EXPECT_LT(rpe.translation.rmse, 1e-9);
  EXPECT_LT(rpe.rotationDeg.rmse, 1e-6);
  const vpHSlamTrajectory aligned = evaluator.getAlignedEstimate(ate);
  ASSERT_EQ(aligned.size(), gt.size());
  for (unsigned int r = 0; r < 3; ++r) {
    for (unsigned int c = 0; c < 4; ++c) {
      EXPECT_NEAR(aligned.get_wMc(42)[r][c], gt.get_wMc(42)[r][c], 1e-9);
    }
  }
  EXPECT_EQ(vpHSlamTrajectoryEvaluator::alignmentFromString("se3"), vpHSlamTrajectoryEvaluator::alignSE3);
  EXPECT_THROW(vpHSlamTrajectoryEvaluator::alignmentFromString("affine"), vpHSlamException);

  vpImage<vpRGBa> I;
  vpHSlamTrajectoryEvaluator::drawTopView(I, gt, aligned, "synthetic", 400, 300);
  EXPECT_EQ(I.getWidth(), 400u);
  EXPECT_EQ(I.getHeight(), 300u);
}
