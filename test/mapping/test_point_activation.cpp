// Point activation: distance map values (exact BFS distances), the minimum-distance adaptation, and a whole
// activation pass on a small window with known geometry.
#include "HSlamTestData.h"

#include "map/Keyframe.h"
#include "mapping/ImmaturePointTracer.h"
#include "mapping/PointActivation.h"

#include <visp3/hslam/vpHSlamParameters.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <memory>
#include <random>
#include <utility>
#include <vector>

namespace
{
using hslam::ActivationPlan;
using hslam::ImmaturePoint;
using hslam::Keyframe;
using hslam::KeyframePtr;
using hslam::PointActivation;
using hslam::TraceStatus;

// Steps of the search to reach offset (a, b) from a seed: odd steps move to any of the 8 neighbours, even steps to
// the 4 neighbours, so k steps reach max(|a|,|b|) <= k and |a| + |b| <= k + ceil(k / 2).
int octagonalSteps(int a, int b)
{
  a = std::abs(a);
  b = std::abs(b);
  for (int k = 0;; ++k) {
    if (std::max(a, b) <= k && a + b <= k + (k + 1) / 2) {
      return k;
    }
  }
}

float expectedDistance(int u, int v, const std::vector<std::pair<int, int>> &seeds)
{
  int best = PointActivation::kMaxSearchSteps;
  for (const auto &s : seeds) {
    best = std::min(best, octagonalSteps(u - s.first, v - s.second));
  }
  return best < PointActivation::kMaxSearchSteps ? static_cast<float>(best) : PointActivation::kFarDistance;
}

TEST(PointActivation, DistanceMapSingleSeedIsOctagonal)
{
  vpHSlamParameters params;
  PointActivation activation(params.mapper);
  constexpr int w = 100, h = 90;
  const std::vector<std::pair<int, int>> seeds = {{50, 45}};
  activation.buildDistanceMap(w, h, seeds);
  ASSERT_EQ(activation.width(), w);
  ASSERT_EQ(activation.height(), h);
  // Spot values: straight, diagonal, knight-like offsets.
  EXPECT_EQ(activation.distanceAt(50, 45), 0.f);
  EXPECT_EQ(activation.distanceAt(51, 46), 1.f);
  EXPECT_EQ(activation.distanceAt(52, 47), 3.f); // a diagonal, then only straight moves on the even step
  EXPECT_EQ(activation.distanceAt(53, 45), 3.f);
  EXPECT_EQ(activation.distanceAt(60, 45), 10.f);
  EXPECT_EQ(activation.distanceAt(60, 55), 13.f); // 7 odd steps (diagonal) + 6 even steps
  // Everywhere the search could reach without touching the border: the closed form.
  int checked = 0;
  for (int v = 1; v < h - 1; ++v) {
    for (int u = 1; u < w - 1; ++u) {
      ASSERT_EQ(activation.distanceAt(u, v), expectedDistance(u, v, seeds)) << u << "," << v;
      ++checked;
    }
  }
  EXPECT_EQ(checked, (w - 2) * (h - 2));
}

TEST(PointActivation, DistanceMapManySeedsAndIncrementalAdd)
{
  vpHSlamParameters params;
  PointActivation activation(params.mapper);
  constexpr int w = 160, h = 120;
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> du(45, w - 46), dv(45, h - 46);
  std::vector<std::pair<int, int>> seeds;
  for (int i = 0; i < 12; ++i) {
    seeds.emplace_back(du(rng), dv(rng));
  }
  // Seeds on the first row/column or outside are ignored (DSO).
  std::vector<std::pair<int, int>> withInvalid = seeds;
  withInvalid.emplace_back(0, 10);
  withInvalid.emplace_back(10, 0);
  withInvalid.emplace_back(w, 5);
  withInvalid.emplace_back(-3, 5);
  activation.buildDistanceMap(w, h, withInvalid);
  int mismatches = 0, far = 0;
  for (int v = 1; v < h - 1; ++v) {
    for (int u = 1; u < w - 1; ++u) {
      mismatches += activation.distanceAt(u, v) != expectedDistance(u, v, seeds);
      far += activation.distanceAt(u, v) == PointActivation::kFarDistance;
    }
  }
  EXPECT_EQ(mismatches, 0);
  EXPECT_GT(far, 0) << "the corners are more than 40 steps away from the central seeds";

  // Adding an activation equals rebuilding with one more seed.
  const std::pair<int, int> extra{60, 70};
  activation.addActivated(extra.first, extra.second);
  seeds.push_back(extra);
  mismatches = 0;
  for (int v = 1; v < h - 1; ++v) {
    for (int u = 1; u < w - 1; ++u) {
      mismatches += activation.distanceAt(u, v) != expectedDistance(u, v, seeds);
    }
  }
  EXPECT_EQ(mismatches, 0);

  // Empty map: everything far.
  activation.buildDistanceMap(w, h, {});
  EXPECT_EQ(activation.distanceAt(80, 60), PointActivation::kFarDistance);
}

TEST(PointActivation, CanActivateUsesLevelAndJitter)
{
  vpHSlamParameters params;
  PointActivation activation(params.mapper);
  EXPECT_FLOAT_EQ(activation.minDistance(), static_cast<float>(params.mapper.activationMinDistance));
  activation.buildDistanceMap(100, 80, {{50, 40}});
  activation.setMinDistance(1.5f);
  // Pixel (53, 40) has distance 3: enough for level 0 (1.5) and level 1 (3), not for level 2 (6).
  EXPECT_TRUE(activation.canActivate(53.f, 40.f, 0));
  EXPECT_TRUE(activation.canActivate(53.f, 40.f, 1));
  EXPECT_FALSE(activation.canActivate(53.f, 40.f, 2));
  // Distance 1 plus the fractional part of u against 1.5 (rounding to the nearest pixel keeps (51, 40)).
  EXPECT_FALSE(activation.canActivate(51.2f, 40.f, 0)); // 1 + 0.2 < 1.5
  EXPECT_TRUE(activation.canActivate(50.9f, 40.f, 0));  // same pixel, 1 + 0.9 >= 1.5
  // Outside the map or on its first row/column.
  EXPECT_FALSE(activation.canActivate(0.f, 40.f, 0));
  EXPECT_FALSE(activation.canActivate(150.f, 40.f, 0));
}

TEST(PointActivation, MinDistanceRuleMatchesDso)
{
  vpHSlamParameters params;
  PointActivation activation(params.mapper);
  const int desired = 2000;
  struct Case {
    int count;
    float change;
  };
  // DSO currentMinActDist: < 66 %: -0.8 - 0.5; < 80 %: -0.5; < 90 %: -0.2; < 100 %: -0.1;
  // > 150 %: +0.8 +0.5 +0.2 +0.1; > 130 %: +0.5 +0.2 +0.1; > 115 %: +0.2 +0.1; > 100 %: +0.1.
  const Case cases[] = {{1000, -1.3f}, {1500, -0.5f}, {1700, -0.2f}, {1900, -0.1f}, {2000, 0.f},
                        {2100, 0.1f},  {2400, 0.3f},  {2700, 0.8f},  {3100, 1.6f}};
  for (const Case &c : cases) {
    activation.setMinDistance(2.f);
    activation.adaptMinDistance(c.count, desired);
    EXPECT_NEAR(activation.minDistance(), 2.f + c.change, 1e-6f) << c.count;
  }
  activation.setMinDistance(0.2f);
  activation.adaptMinDistance(0, desired);
  EXPECT_EQ(activation.minDistance(), 0.f);
  activation.setMinDistance(3.9f);
  activation.adaptMinDistance(10 * desired, desired);
  EXPECT_EQ(activation.minDistance(), 4.f);
}

// Closed loop: each "keyframe" activates greedily from the same dense candidate set, the count feeds the rule.
TEST(PointActivation, AdaptationConvergesToDesiredCount)
{
  vpHSlamParameters params;
  constexpr int w = 160, h = 120;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> du(1.f, w - 1.5f), dv(1.f, h - 1.5f);
  std::vector<std::pair<float, float>> candidates(6000);
  for (auto &c : candidates) {
    c = {du(rng), dv(rng)};
  }
  // Greedy activation count as a function of the minimum distance: 6000 at 0, about 700 at the upper bound 4.
  const auto activate = [&candidates](PointActivation &activation) {
    activation.buildDistanceMap(w, h, {});
    int count = 0;
    for (const auto &c : candidates) {
      if (activation.canActivate(c.first, c.second, 0)) {
        activation.addActivated(static_cast<int>(std::floor(c.first + 0.5f)),
                                static_cast<int>(std::floor(c.second + 0.5f)));
        ++count;
      }
    }
    return count;
  };
  for (const int desired : {1000, 1800, 3000}) {
    PointActivation activation(params.mapper);
    activation.setMinDistance(0.f);
    int count = 0;
    std::vector<int> errors;
    for (int keyframe = 0; keyframe < 25; ++keyframe) {
      count = activate(activation);
      errors.push_back(std::abs(count - desired));
      activation.adaptMinDistance(count, desired);
    }
    // Starts far off (every candidate activates at distance 0), ends within 20 % of the target.
    EXPECT_GE(errors.front(), desired) << desired;
    EXPECT_LT(errors.back(), desired / 5) << desired << ": final count " << count;
    EXPECT_LT(*std::max_element(errors.end() - 5, errors.end()), desired / 5) << desired;
  }
  // A target below what the largest distance allows: the distance saturates at its upper bound.
  PointActivation saturated(params.mapper);
  for (int keyframe = 0; keyframe < 10; ++keyframe) {
    saturated.adaptMinDistance(activate(saturated), 100);
  }
  EXPECT_EQ(saturated.minDistance(), 4.f);
}

// A window of two keyframes with known poses: host 0 translated 10 cm to the left of the newest keyframe 1.
struct Window {
  std::vector<KeyframePtr> keyframes;
  hslam::PinholeIntrinsics K{200., 200., 79.5, 59.5};
};

Window makeWindow()
{
  Window window;
  vpImage<float> I(120, 160, 100.f);
  for (int k = 0; k < 2; ++k) {
    auto frame = std::make_shared<hslam::Frame>();
    frame->id = frame->keyframeId = k;
    frame->cMw = hslam::SE3d(Eigen::Matrix3d::Identity(), Eigen::Vector3d(k == 0 ? 0.1 : 0., 0., 0.));
    frame->pyramid.build(I, window.K, 3, 100);
    auto kf = std::make_shared<Keyframe>();
    kf->frame = frame;
    window.keyframes.push_back(kf);
  }
  return window;
}

ImmaturePoint readyPoint(float u, float v, float idepth, float halfWidth)
{
  ImmaturePoint pt;
  pt.hostKeyframeId = 0;
  pt.u = u;
  pt.v = v;
  pt.idepthMin = idepth - halfWidth;
  pt.idepthMax = idepth + halfWidth;
  pt.quality = 10.f;
  pt.lastStatus = TraceStatus::good;
  pt.patch.fill(100.f);
  pt.patchWeight.fill(0.5f);
  return pt;
}

TEST(PointActivation, SelectPointsOnWindow)
{
  vpHSlamParameters params;
  Window window = makeWindow();
  Keyframe &host = *window.keyframes[0];
  const Keyframe &newest = *window.keyframes[1];
  // Newest camera = host camera shifted by -0.1 m in x: a host pixel moves by -200 * 0.1 * idepth pixels.
  // One active point at host (60, 60), idepth 1: at (40, 60) in the newest keyframe, (20, 30) in the map.
  hslam::MapPoint active;
  active.hostKeyframeId = 0;
  active.u = 60.f;
  active.v = 60.f;
  active.idepth = 1.;
  host.points.push_back(active);

  host.immature.push_back(readyPoint(61.f, 60.f, 1.f, 0.01f));  // 0: 1 px from the active point: too close
  host.immature.push_back(readyPoint(100.f, 60.f, 1.f, 0.01f)); // 1: far: activated
  host.immature.push_back(readyPoint(101.f, 61.f, 1.f, 0.01f)); // 2: next to 1, activated after it: too close
  ImmaturePoint untraced = readyPoint(120.f, 20.f, 1.f, 0.01f);
  untraced.idepthMax = std::numeric_limits<float>::infinity();
  host.immature.push_back(untraced); // 3: never traced: dropped
  ImmaturePoint wide = readyPoint(120.f, 90.f, 1.f, 0.5f);
  host.immature.push_back(wide); // 4: interval of 20 px in the newest keyframe: not ready, kept
  ImmaturePoint ambiguous = readyPoint(130.f, 100.f, 1.f, 0.01f);
  ambiguous.quality = 2.f;
  host.immature.push_back(ambiguous);                          // 5: quality below 3: not ready, kept
  host.immature.push_back(readyPoint(10.f, 60.f, 1.f, 0.01f)); // 6: projects to u = -10: dropped
  ImmaturePoint outlier = readyPoint(140.f, 30.f, 1.f, 0.01f);
  outlier.lastStatus = TraceStatus::outlier;
  host.immature.push_back(outlier); // 7: outlier: dropped

  PointActivation activation(params.mapper);
  activation.setMinDistance(2.f);
  activation.buildDistanceMap(window.keyframes, newest);
  ASSERT_EQ(activation.width(), 80);
  ASSERT_EQ(activation.height(), 60);
  EXPECT_EQ(activation.distanceAt(20, 30), 0.f);
  EXPECT_EQ(activation.distanceAt(25, 30), 5.f);

  const ActivationPlan plan = activation.selectPoints(window.keyframes, newest);
  ASSERT_EQ(plan.activate.size(), 1u);
  EXPECT_EQ(plan.activate[0].ref.pointIndex, 1);
  EXPECT_EQ(plan.activate[0].ref.windowIndex, 0);
  EXPECT_FLOAT_EQ(plan.activate[0].idepth, 1.f);
  EXPECT_NEAR(plan.activate[0].uNewest, 80.f, 1e-3f);
  EXPECT_NEAR(plan.activate[0].vNewest, 60.f, 1e-3f);
  std::vector<int> dropped;
  for (const auto &ref : plan.drop) {
    dropped.push_back(ref.pointIndex);
  }
  std::sort(dropped.begin(), dropped.end());
  EXPECT_EQ(dropped, (std::vector<int>{3, 6, 7}));

  // The map point made from the candidate starts at the interval centre with the uniform variance.
  const hslam::MapPoint p = PointActivation::makeMapPoint(host.immature[1]);
  EXPECT_FLOAT_EQ(static_cast<float>(p.idepth), 1.f);
  EXPECT_NEAR(p.idepthVar, 0.02 * 0.02 / 12., 1e-9);
  EXPECT_EQ(p.status, hslam::PointStatus::active);

  // Erase activated + dropped: the others keep their order.
  std::vector<hslam::ImmaturePointRef> erase = plan.drop;
  erase.push_back(plan.activate[0].ref);
  erase.push_back(plan.activate[0].ref); // duplicates are harmless
  PointActivation::eraseImmaturePoints(window.keyframes, erase);
  ASSERT_EQ(host.immature.size(), 4u);
  EXPECT_EQ(host.immature[0].u, 61.f);
  EXPECT_EQ(host.immature[1].u, 101.f);
  EXPECT_EQ(host.immature[2].u, 120.f);
  EXPECT_EQ(host.immature[3].u, 130.f);
}

TEST(PointActivation, DescriptorOnlyPointsAreNeverActivatedButDroppedAlike)
{
  // The first keyframe's corners (LocalMapper::initialize): traced for their depth only.
  vpHSlamParameters params;
  Window window = makeWindow();
  Keyframe &host = *window.keyframes[0];
  const Keyframe &newest = *window.keyframes[1];
  ImmaturePoint kept = readyPoint(100.f, 60.f, 1.f, 0.01f); // ready, far from anything: activated if it could be
  kept.descriptorOnly = true;
  ImmaturePoint outside = readyPoint(10.f, 60.f, 1.f, 0.01f); // projects out of the newest keyframe
  outside.descriptorOnly = true;
  host.immature = {kept, outside, readyPoint(100.f, 20.f, 1.f, 0.01f)};
  PointActivation activation(params.mapper);
  activation.setMinDistance(2.f);
  activation.buildDistanceMap(window.keyframes, newest);
  const ActivationPlan plan = activation.selectPoints(window.keyframes, newest);
  ASSERT_EQ(plan.activate.size(), 1u);
  EXPECT_EQ(plan.activate[0].ref.pointIndex, 2) << "the ordinary point only";
  ASSERT_EQ(plan.drop.size(), 1u);
  EXPECT_EQ(plan.drop[0].pointIndex, 1);

  // What may stand for a map point when its host leaves: a good, unambiguous trace and an interval within +-10 %.
  const float minQuality = static_cast<float>(params.mapper.minTraceQuality);
  EXPECT_TRUE(hslam::hasConvergedDepth(kept, minQuality));
  ImmaturePoint wide = readyPoint(100.f, 60.f, 1.f, 0.11f);
  EXPECT_FALSE(hslam::hasConvergedDepth(wide, minQuality));
  wide = readyPoint(100.f, 60.f, 1.f, 0.09f);
  EXPECT_TRUE(hslam::hasConvergedDepth(wide, minQuality));
  ImmaturePoint ambiguous = kept;
  ambiguous.quality = minQuality;
  EXPECT_FALSE(hslam::hasConvergedDepth(ambiguous, minQuality));
  for (const TraceStatus s : {TraceStatus::skipped, TraceStatus::outlier, TraceStatus::uninitialized}) {
    ImmaturePoint notGood = kept;
    notGood.lastStatus = s;
    EXPECT_FALSE(hslam::hasConvergedDepth(notGood, minQuality));
  }
  ImmaturePoint untraced = kept;
  untraced.idepthMax = std::numeric_limits<float>::infinity();
  EXPECT_FALSE(hslam::hasConvergedDepth(untraced, minQuality));
}

TEST(PointActivation, ReadinessFollowsDso)
{
  vpHSlamParameters params;
  const PointActivation activation(params.mapper);
  ImmaturePoint pt = readyPoint(10.f, 10.f, 1.f, 0.01f);
  EXPECT_TRUE(activation.isReady(pt, 1.f));
  EXPECT_FALSE(activation.isReady(pt, static_cast<float>(params.mapper.maxTraceInterval)));
  for (const TraceStatus s : {TraceStatus::skipped, TraceStatus::badCondition, TraceStatus::outOfBounds}) {
    pt.lastStatus = s;
    EXPECT_TRUE(activation.isReady(pt, 1.f));
  }
  for (const TraceStatus s : {TraceStatus::outlier, TraceStatus::uninitialized}) {
    pt.lastStatus = s;
    EXPECT_FALSE(activation.isReady(pt, 1.f));
  }
  pt.lastStatus = TraceStatus::good;
  pt.quality = static_cast<float>(params.mapper.minTraceQuality);
  EXPECT_FALSE(activation.isReady(pt, 1.f)) << "quality must exceed the minimum";
  // Interval length measured in the newest keyframe, as the activation pass does.
  const hslam::PinholeIntrinsics K{200., 200., 79.5, 59.5};
  const hslam::SE3d newestMhost(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.1, 0., 0.));
  EXPECT_NEAR(hslam::ImmaturePointTracer::projectedIntervalLength(readyPoint(60.f, 60.f, 1.f, 0.5f), newestMhost, K),
              20.f, 1e-3f);
}
} // namespace
