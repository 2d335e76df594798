// Global inverse-depth bundle adjustment (issue 10): on a synthetic ring of keyframes with exact measurements,
// perturbed poses and inverse depths are recovered; gross outliers are held off by the robust loss; bad input is
// left out rather than crashing the solver; the job built from a global map writes its solution back, and runs on
// a thread of its own (real-time mode), where it can be cancelled; the solution does not depend on memory layout.
#include "loop/GlobalBundleAdjustment.h"
#include "loop/GlobalBundleJob.h"

#include "HSlamTestCameras.h"

#include <visp3/hslam/vpHSlamException.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <vector>

namespace
{
using hslam::BundlePoint;
using hslam::GlobalBundleAdjustment;
using hslam::PinholeIntrinsics;
using hslam::SE3d;

//! Eight keyframes on a circle of radius 2 m around the origin, all looking at it, and points in a 1 m cube.
struct Ring {
  PinholeIntrinsics K = hslam_test::vgaPinhole500();
  std::vector<SE3d> cMw;
  std::vector<Eigen::Vector3d> wX;

  explicit Ring(unsigned seed)
  {
    for (int k = 0; k < 8; ++k) {
      const double a = 0.25 * M_PI * k / 4.; // a 45 degree arc: every keyframe sees the centre
      const Eigen::Vector3d centre(2. * std::sin(a), 0.1 * k / 8., -2. * std::cos(a));
      const Eigen::Vector3d z = (-centre).normalized();
      const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
      const Eigen::Vector3d y = z.cross(x);
      Eigen::Matrix3d wRc;
      wRc << x, y, z;
      cMw.push_back(SE3d(wRc.transpose(), -(wRc.transpose() * centre)));
    }
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-0.5, 0.5);
    for (int i = 0; i < 400; ++i) {
      wX.emplace_back(u(rng), u(rng), u(rng));
    }
  }

  bool project(int k, const Eigen::Vector3d &X, Eigen::Vector2d &uv) const
  {
    const Eigen::Vector3d c = cMw[static_cast<size_t>(k)] * X;
    uv = Eigen::Vector2d(K.fx * c.x() / c.z() + K.cx, K.fy * c.y() / c.z() + K.cy);
    return c.z() > 0.1 && uv.x() >= 0. && uv.y() >= 0. && uv.x() < 640. && uv.y() < 480.;
  }

  //! Point i hosted in keyframe i % 8, observed (exactly) by every other keyframe that sees it.
  BundlePoint point(size_t i) const
  {
    BundlePoint p;
    p.hostId = static_cast<int>(i % cMw.size());
    Eigen::Vector2d uv;
    project(p.hostId, wX[i], uv);
    p.u = uv.x();
    p.v = uv.y();
    p.idepth = 1. / (cMw[static_cast<size_t>(p.hostId)] * wX[i]).z();
    for (int k = 0; k < static_cast<int>(cMw.size()); ++k) {
      if (k != p.hostId && project(k, wX[i], uv)) {
        p.observations.push_back({k, uv.x(), uv.y()});
      }
    }
    return p;
  }
};

SE3d perturbed(const SE3d &T, std::mt19937 &rng, double trans, double rot)
{
  std::normal_distribution<double> n(0., 1.);
  SE3d::Tangent xi;
  xi << trans * n(rng), trans * n(rng), trans * n(rng), rot * n(rng), rot * n(rng), rot * n(rng);
  return SE3d::exp(xi) * T;
}

TEST(GlobalBundleAdjustment, RecoversPerturbedPosesAndInverseDepths)
{
  const Ring ring(1);
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0., 1.);
  GlobalBundleAdjustment ba(ring.K);
  for (int k = 0; k < 8; ++k) {
    // Keyframes 6 and 7 hold the gauge (the "window"); the rest start 5 cm / 1 degree off.
    const bool fixed = k >= 6;
    ba.addKeyframe(
        k, fixed ? ring.cMw[static_cast<size_t>(k)] : perturbed(ring.cMw[static_cast<size_t>(k)], rng, 0.05, 0.017),
        fixed);
  }
  std::vector<int> index;
  std::vector<double> truth;
  for (size_t i = 0; i < ring.wX.size(); ++i) {
    BundlePoint p = ring.point(i);
    truth.push_back(p.idepth);
    p.idepth *= 1. + 0.1 * n(rng);
    index.push_back(ba.addPoint(p));
    ASSERT_GE(index.back(), 0);
  }
  hslam::GlobalBundleOptions options;
  options.maxIterations = 50;
  const hslam::GlobalBundleSummary s = ba.optimize(options);
  ASSERT_TRUE(s.usable);
  EXPECT_EQ(s.keyframes, 8);
  EXPECT_EQ(s.points, 400);
  EXPECT_GT(s.rmsBeforePx, 5.);
  EXPECT_LT(s.rmsAfterPx, 1e-3);
  for (int k = 0; k < 8; ++k) {
    const SE3d e = ba.keyframe(k) * ring.cMw[static_cast<size_t>(k)].inverse();
    EXPECT_LT(e.translation().norm(), 1e-5) << "keyframe " << k;
    EXPECT_LT(e.log().tail<3>().norm(), 1e-6) << "keyframe " << k;
  }
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_NEAR(ba.idepth(index[i]), truth[i], 1e-5 * truth[i]) << "point " << i;
  }
  // Fixed keyframes did not move.
  EXPECT_EQ(ba.keyframe(7).translation(), ring.cMw[7].translation());
}

TEST(GlobalBundleAdjustment, SolutionDoesNotDependOnInsertionOrderOrHeapLayout)
{
  // The same problem built twice, keyframes added in opposite orders with other allocations in between (so their
  // storage lies in another order in memory): the solutions must be bit-identical. Ceres orders the blocks of an
  // elimination group by address; before the poses were solved in a buffer of their own, the second solution
  // differed in the last digits, and a slam run's output changed with its caller's allocations.
  const Ring ring(3);
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0., 1.);
  std::vector<SE3d> start;
  for (int k = 0; k < 8; ++k) {
    start.push_back(k >= 6 ? ring.cMw[static_cast<size_t>(k)]
                           : perturbed(ring.cMw[static_cast<size_t>(k)], rng, 0.05, 0.017));
  }
  std::vector<BundlePoint> points;
  for (size_t i = 0; i < ring.wX.size(); ++i) {
    BundlePoint p = ring.point(i);
    p.idepth *= 1. + 0.1 * n(rng);
    for (BundlePoint::Observation &o : p.observations) { // noisy pixels: the optimum is not exact
      o.u += 0.5 * n(rng);
      o.v += 0.5 * n(rng);
    }
    points.push_back(p);
  }
  hslam::GlobalBundleOptions options;
  options.maxIterations = 4;
  std::vector<std::unique_ptr<std::vector<char>>> clutter;
  auto solve = [&](bool reversed) {
    auto ba = std::make_unique<GlobalBundleAdjustment>(ring.K);
    for (int j = 0; j < 8; ++j) {
      const int k = reversed ? 7 - j : j;
      ba->addKeyframe(k, start[static_cast<size_t>(k)], k >= 6);
      clutter.push_back(std::make_unique<std::vector<char>>(static_cast<size_t>(64 + 48 * j)));
    }
    for (const BundlePoint &p : points) {
      EXPECT_GE(ba->addPoint(p), 0);
    }
    EXPECT_TRUE(ba->optimize(options).usable);
    return ba;
  };
  const std::unique_ptr<GlobalBundleAdjustment> a = solve(false);
  const std::unique_ptr<GlobalBundleAdjustment> b = solve(true);
  int differing = 0;
  for (int k = 0; k < 8; ++k) {
    differing += a->keyframe(k).matrix() == b->keyframe(k).matrix() ? 0 : 1;
  }
  for (int i = 0; i < static_cast<int>(points.size()); ++i) {
    differing += a->idepth(i) == b->idepth(i) ? 0 : 1;
  }
  EXPECT_EQ(differing, 0);
}

TEST(GlobalBundleAdjustment, GrossOutliersAreHeldOffByTheRobustLoss)
{
  const Ring ring(3);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> off(-40., 40.);
  GlobalBundleAdjustment ba(ring.K);
  for (int k = 0; k < 8; ++k) {
    const bool fixed = k >= 6;
    ba.addKeyframe(
        k, fixed ? ring.cMw[static_cast<size_t>(k)] : perturbed(ring.cMw[static_cast<size_t>(k)], rng, 0.03, 0.01),
        fixed);
  }
  int outliers = 0, total = 0;
  for (size_t i = 0; i < ring.wX.size(); ++i) {
    BundlePoint p = ring.point(i);
    for (BundlePoint::Observation &o : p.observations) {
      ++total;
      if (rng() % 20 == 0) { // 5 % of the measurements are wrong by up to 40 px
        o.u += off(rng);
        o.v += off(rng);
        ++outliers;
      }
    }
    ba.addPoint(p);
  }
  ASSERT_GT(outliers, total / 40);
  hslam::GlobalBundleOptions options;
  options.maxIterations = 50;
  const hslam::GlobalBundleSummary s = ba.optimize(options);
  ASSERT_TRUE(s.usable);
  EXPECT_LT(s.rmsAfterPx, s.rmsBeforePx);
  for (int k = 0; k < 6; ++k) {
    const SE3d e = ba.keyframe(k) * ring.cMw[static_cast<size_t>(k)].inverse();
    EXPECT_LT(e.translation().norm(), 2e-3) << "keyframe " << k; // 3 cm perturbations brought to millimetres
  }
}

TEST(GlobalBundleAdjustment, UnusableInputIsLeftOut)
{
  const Ring ring(5);
  GlobalBundleAdjustment ba(ring.K);
  for (int k = 0; k < 8; ++k) {
    ba.addKeyframe(k, ring.cMw[static_cast<size_t>(k)], k >= 6);
  }
  BundlePoint p = ring.point(0);
  BundlePoint unknownHost = p;
  unknownHost.hostId = 42;
  EXPECT_EQ(ba.addPoint(unknownHost), -1);
  BundlePoint negative = p;
  negative.idepth = -1.;
  EXPECT_EQ(ba.addPoint(negative), -1);
  BundlePoint unmeasured = p;
  for (BundlePoint::Observation &o : unmeasured.observations) {
    o.u = std::numeric_limits<double>::quiet_NaN(); // unknown pixels (a version-1 map file)
  }
  EXPECT_EQ(ba.addPoint(unmeasured), -1);
  BundlePoint behind = p;
  behind.observations.push_back({p.hostId, p.u, p.v}); // the host itself: not an observation
  behind.observations.push_back({99, 10., 10.});       // a keyframe not in the problem
  const int kept = ba.addPoint(behind);
  ASSERT_GE(kept, 0);
  // Exact data: nothing to do, and the solution is where it was.
  const hslam::GlobalBundleSummary s = ba.optimize(hslam::GlobalBundleOptions());
  EXPECT_TRUE(s.usable);
  EXPECT_EQ(s.observations, static_cast<int>(p.observations.size()));
  EXPECT_LT(s.rmsAfterPx, 1e-6);
  EXPECT_THROW(ba.keyframe(42), vpHSlamException);
  // An empty problem is a no-op.
  GlobalBundleAdjustment empty(ring.K);
  EXPECT_TRUE(empty.optimize(hslam::GlobalBundleOptions()).usable);
}

//! The ring as a global map: keyframes 0-5 stored (segment 0) at perturbed poses, 6 and 7 the "window".
struct RingMap {
  Ring ring{7};
  hslam::GlobalMap map;
  std::map<int, SE3d> window;

  RingMap()
  {
    std::mt19937 rng(8);
    for (int k = 0; k < 8; ++k) {
      if (k >= 6) {
        window[k] = ring.cMw[static_cast<size_t>(k)];
        continue;
      }
      hslam::GlobalKeyframe kf;
      kf.id = k;
      kf.cMw = perturbed(ring.cMw[static_cast<size_t>(k)], rng, 0.03, 0.01);
      for (size_t i = static_cast<size_t>(k); i < ring.wX.size(); i += 8) {
        const BundlePoint b = ring.point(i);
        hslam::GlobalPoint p;
        p.u = static_cast<float>(b.u);
        p.v = static_cast<float>(b.v);
        p.idepth = static_cast<float>(b.idepth * 1.05);
        p.idepthVar = 1e-4f;
        p.isCorner = i % 2 == 0;
        for (const BundlePoint::Observation &o : b.observations) {
          p.observers.push_back(o.keyframeId);
          p.observedAt.push_back({static_cast<float>(o.u), static_cast<float>(o.v)});
        }
        kf.points.push_back(p);
      }
      map.add(kf);
    }
  }

  double worstCentreError() const
  {
    double worst = 0.;
    for (const auto &entry : map.keyframes()) {
      if (entry.second.segment != 0) {
        continue; // not one of the ring's keyframes
      }
      const SE3d &T = entry.second.cMw;
      const SE3d &truth = ring.cMw[static_cast<size_t>(entry.first)];
      worst = std::max(worst, (T.inverse().translation() - truth.inverse().translation()).norm());
    }
    return worst;
  }
};

TEST(GlobalBundleJob, BuildsFromTheGlobalMapAndWritesBack)
{
  RingMap rm;
  hslam::GlobalBundleOptions options;
  options.maxIterations = 30;
  const double before = rm.worstCentreError();
  ASSERT_GT(before, 0.02);
  // Another segment's keyframes are not part of the job.
  hslam::GlobalKeyframe other;
  other.id = 50;
  other.segment = 1;
  rm.map.add(other);
  std::unique_ptr<hslam::GlobalBundleJob> job = hslam::makeGlobalBundleJob(rm.map, 0, rm.window, rm.ring.K, options, 0);
  EXPECT_EQ(job->keyframes, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  job->run();
  ASSERT_TRUE(job->summary.usable);
  EXPECT_LT(job->summary.rmsAfterPx, 1e-3 * job->summary.rmsBeforePx);
  EXPECT_EQ(hslam::applyGlobalBundleJob(*job, rm.map), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  // The map's keyframes are where they belong again (floats for the stored pixels: sub-millimetre, not exact).
  EXPECT_LT(rm.worstCentreError(), 1e-3);

  // A point budget per keyframe: only the most observed points are adjusted.
  RingMap budget;
  std::unique_ptr<hslam::GlobalBundleJob> small =
      hslam::makeGlobalBundleJob(budget.map, 0, budget.window, budget.ring.K, options, 10);
  EXPECT_EQ(small->problem.pointCount(), 60u);
}

TEST(BackgroundBundleAdjustment, RunsOnItsOwnThreadAndCanBeCancelled)
{
  RingMap rm;
  hslam::GlobalBundleOptions options;
  options.maxIterations = 30;
  hslam::BackgroundBundleAdjustment background;
  EXPECT_FALSE(background.running());
  EXPECT_EQ(background.take(), nullptr);
  // Started, then replaced by a second job (the first is cancelled), which is waited for.
  background.start(hslam::makeGlobalBundleJob(rm.map, 0, rm.window, rm.ring.K, options, 0));
  background.start(hslam::makeGlobalBundleJob(rm.map, 0, rm.window, rm.ring.K, options, 0));
  EXPECT_TRUE(background.running());
  std::unique_ptr<hslam::GlobalBundleJob> job = background.take();
  ASSERT_NE(job, nullptr);
  EXPECT_FALSE(background.running());
  ASSERT_TRUE(job->summary.usable);
  hslam::applyGlobalBundleJob(*job, rm.map);
  EXPECT_LT(rm.worstCentreError(), 1e-3);
  // Cancelled before it could end: nothing to take, nothing changed.
  RingMap again;
  const double before = again.worstCentreError();
  hslam::GlobalBundleOptions many = options;
  many.maxIterations = 1000;
  background.start(hslam::makeGlobalBundleJob(again.map, 0, again.window, again.ring.K, many, 0));
  background.cancel();
  EXPECT_FALSE(background.running());
  EXPECT_EQ(background.take(), nullptr);
  EXPECT_EQ(again.worstCentreError(), before);
  // A cancelled solve reports an unusable solution and keeps the estimates.
  std::atomic<bool> stop{true};
  hslam::GlobalBundleOptions stopped = options;
  stopped.cancel = &stop;
  std::unique_ptr<hslam::GlobalBundleJob> direct =
      hslam::makeGlobalBundleJob(again.map, 0, again.window, again.ring.K, stopped, 0);
  direct->run();
  EXPECT_FALSE(direct->summary.usable);
  EXPECT_TRUE(hslam::applyGlobalBundleJob(*direct, again.map).empty());
  EXPECT_EQ(again.worstCentreError(), before);
}
} // namespace
