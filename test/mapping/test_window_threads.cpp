/*
 * H-SLAM for ViSP.
 */
// Window BA split over worker threads (system.workerThreads): same optimum as the single-threaded path up to the
// reordering of sums, and bit-identical run to run for a given thread count.
#include "HSlamTestData.h"
#include "WindowTestScene.h"

#include "mapping/WindowOptimizer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace hslam;
using hslam_test::TestScene;

namespace
{
constexpr int kKeyframes = 5;
constexpr unsigned int kFrameStep = 4;
constexpr int kPointsPerKeyframe = 200;
constexpr int kIterations = 8;
//! Different thread counts only reorder floating-point sums: the results agree to round-off.
constexpr double kRelativeTolerance = 1e-9;

struct Result {
  std::vector<SE3d> cMw;
  std::vector<double> a, b, idepth;
  OptimizationSummary summary;
};

//! Build the same perturbed synthetic window and optimise it with \e threads workers.
Result optimizeWindow(int threads)
{
  TestScene scene;
  std::vector<KeyframePtr> kfs;
  for (int k = 0; k < kKeyframes; ++k) {
    kfs.push_back(scene.makeKeyframe(static_cast<unsigned int>(k) * kFrameStep, k, kPointsPerKeyframe));
  }
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> sign(-1., 1.);
  for (size_t k = 1; k < kfs.size(); ++k) {
    Eigen::Matrix<double, 6, 1> xi;
    for (int i = 0; i < 6; ++i) {
      xi[i] = (i < 3 ? 0.01 : 0.005) * sign(rng);
    }
    kfs[k]->frame->cMw = SE3d::exp(xi) * kfs[k]->frame->cMw;
    kfs[k]->frame->affine.a = 0.02 * sign(rng);
    kfs[k]->frame->affine.b = 2. * sign(rng);
  }
  for (auto &kf : kfs) {
    for (MapPoint &p : kf->points) {
      p.idepth *= 1. + 0.1 * sign(rng);
    }
  }
  vpHSlamParameters params = scene.params;
  params.system.workerThreads = threads;
  WindowOptimizer opt(params);
  for (auto &kf : kfs) {
    opt.addKeyframe(kf);
  }
  Result r;
  r.summary = opt.optimize(kIterations);
  for (auto &kf : kfs) {
    r.cMw.push_back(kf->frame->cMw);
    r.a.push_back(kf->frame->affine.a);
    r.b.push_back(kf->frame->affine.b);
    for (const MapPoint &p : kf->points) {
      r.idepth.push_back(p.idepth);
    }
  }
  return r;
}

double relDiff(double x, double y)
{
  return std::fabs(x - y) / std::max(1., std::max(std::fabs(x), std::fabs(y)));
}
} // namespace

TEST(WindowThreads, TwoThreadsMatchCallerOnlyPath)
{
  const Result r0 = optimizeWindow(0);
  const Result r2 = optimizeWindow(2);
  ASSERT_GT(r0.summary.activePoints, 500);
  ASSERT_GT(r0.summary.acceptedSteps, 0);
  EXPECT_EQ(r0.summary.iterations, r2.summary.iterations);
  EXPECT_EQ(r0.summary.acceptedSteps, r2.summary.acceptedSteps);
  EXPECT_EQ(r0.summary.inlierResiduals, r2.summary.inlierResiduals);
  EXPECT_LT(relDiff(r0.summary.finalEnergy, r2.summary.finalEnergy), kRelativeTolerance);
  double maxPose = 0., maxIdepth = 0.;
  for (size_t k = 0; k < r0.cMw.size(); ++k) {
    const Eigen::Matrix4d d = r0.cMw[k].matrix() - r2.cMw[k].matrix();
    maxPose = std::max(maxPose, d.cwiseAbs().maxCoeff());
    EXPECT_LT(relDiff(r0.a[k], r2.a[k]), kRelativeTolerance);
    EXPECT_LT(relDiff(r0.b[k], r2.b[k]), kRelativeTolerance);
  }
  ASSERT_EQ(r0.idepth.size(), r2.idepth.size());
  for (size_t i = 0; i < r0.idepth.size(); ++i) {
    maxIdepth = std::max(maxIdepth, std::fabs(r0.idepth[i] - r2.idepth[i]) / std::fabs(r0.idepth[i]));
  }
  std::printf("0 vs 2 threads: %d its, max pose diff %.3g, max rel idepth diff %.3g\n", r0.summary.iterations, maxPose,
              maxIdepth);
  EXPECT_LT(maxPose, kRelativeTolerance);
  EXPECT_LT(maxIdepth, kRelativeTolerance);
}

TEST(WindowThreads, TwoThreadRunsAreBitIdentical)
{
  const Result a = optimizeWindow(2);
  const Result b = optimizeWindow(2);
  ASSERT_GT(a.summary.acceptedSteps, 0);
  EXPECT_EQ(a.summary.finalEnergy, b.summary.finalEnergy);
  for (size_t k = 0; k < a.cMw.size(); ++k) {
    EXPECT_TRUE(a.cMw[k].matrix() == b.cMw[k].matrix()) << "keyframe " << k;
    EXPECT_EQ(a.a[k], b.a[k]);
    EXPECT_EQ(a.b[k], b.b[k]);
  }
  ASSERT_EQ(a.idepth.size(), b.idepth.size());
  size_t differing = 0;
  for (size_t i = 0; i < a.idepth.size(); ++i) {
    differing += a.idepth[i] != b.idepth[i] ? 1 : 0;
  }
  EXPECT_EQ(differing, 0u);
}
