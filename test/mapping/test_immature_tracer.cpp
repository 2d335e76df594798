// Immature point creation and epipolar tracing, checked against exact ground truth: an analytic textured plane
// (exact sub-pixel shifts) and the synthetic room (exact poses and depths).
#include "HSlamTestData.h"

#include "map/Frame.h"
#include "map/ImmaturePoint.h"
#include "mapping/ImmaturePointTracer.h"
#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

namespace
{
using hslam::Frame;
using hslam::FramePtr;
using hslam::ImmaturePoint;
using hslam::ImmaturePointTracer;
using hslam::PinholeIntrinsics;
using hslam::SE3d;
using hslam::TraceResult;
using hslam::TraceStatus;

constexpr unsigned int kWidth = 320, kHeight = 240;
constexpr unsigned int kSceneFrames = 300; // per-frame motion about 1.2 cm: 10 frames give a useful baseline
constexpr unsigned int kLastTarget = 10;
constexpr unsigned int kFirstChecked = 3;
constexpr int kPyramidLevels = 4;
constexpr int kMinCoarsestPixels = 1000;
constexpr int kPointGridStep = 3;
constexpr int kDefaultMargin = 8; // pixels from the border
constexpr int kBorderMargin = 4;  // for points meant to leave the image              // candidate pixels every 3 pixels
constexpr float kMinGradientNorm = 15.f;       // "pixel with gradient", intensity units per pixel
constexpr double kMaxRelativeDepthStep = 0.05; // pattern within 5 % depth: no occlusion boundary at the host
constexpr double kVisibleRelativeDepth = 0.01; // target sees the same surface point
constexpr double kMinContainment = 0.95;

PinholeIntrinsics intrinsicsOf(const vpHSlamSyntheticScene &scene)
{
  const vpCameraParameters cam = scene.getCameraParameters();
  PinholeIntrinsics K;
  K.fx = cam.get_px();
  K.fy = cam.get_py();
  K.cx = cam.get_u0();
  K.cy = cam.get_v0();
  return K;
}

FramePtr makeFrame(const vpHSlamSyntheticScene &scene, unsigned int i, float gain = 1.f, float offset = 0.f)
{
  vpImage<unsigned char> I;
  scene.render(i, I);
  vpImage<float> If(I.getHeight(), I.getWidth());
  for (unsigned int n = 0; n < I.getSize(); ++n) {
    If.bitmap[n] = gain * static_cast<float>(I.bitmap[n]) + offset;
  }
  FramePtr frame = std::make_shared<Frame>();
  frame->id = static_cast<int>(i);
  frame->keyframeId = static_cast<int>(i);
  frame->cMw = hslam::toSE3(scene.getPose(i).inverse());
  frame->pyramid.build(If, intrinsicsOf(scene), kPyramidLevels, kMinCoarsestPixels);
  return frame;
}

// Shared scene and frames 0..kLastTarget (rendering dominates the run time).
class SyntheticTracing : public ::testing::Test
{
protected:
  static void SetUpTestSuite()
  {
    s_scene = new vpHSlamSyntheticScene();
    s_scene->configure(kWidth, kHeight, kSceneFrames, 30.0, 1);
    s_frames = new std::vector<FramePtr>();
    for (unsigned int i = 0; i <= kLastTarget; ++i) {
      s_frames->push_back(makeFrame(*s_scene, i));
    }
  }
  static void TearDownTestSuite()
  {
    delete s_frames;
    delete s_scene;
    s_frames = nullptr;
    s_scene = nullptr;
  }

  // Points on gradient pixels of frame 0 whose pattern lies on one surface (no depth discontinuity).
  std::vector<ImmaturePoint> makePoints(const ImmaturePointTracer &tracer, std::vector<double> &trueIdepth,
                                        int margin = kDefaultMargin, unsigned int hostIndex = 0) const
  {
    const Frame &host = *(*s_frames)[hostIndex];
    const hslam::PyramidLevel &level0 = host.pyramid.level(0);
    std::vector<ImmaturePoint> points;
    for (int v = margin; v < level0.height - margin; v += kPointGridStep) {
      for (int u = margin; u < level0.width - margin; u += kPointGridStep) {
        if (level0.gradSq[static_cast<size_t>(v * level0.width + u)] < kMinGradientNorm * kMinGradientNorm) {
          continue;
        }
        const double depth = s_scene->depthAt(u, v, hostIndex);
        bool smooth = true;
        for (int k = 0; k < hslam::kPatternSize && smooth; ++k) {
          const double d = s_scene->depthAt(u + hslam::kPattern[k][0], v + hslam::kPattern[k][1], hostIndex);
          smooth = std::fabs(d - depth) < kMaxRelativeDepthStep * depth;
        }
        ImmaturePoint pt;
        if (!smooth || !tracer.createImmaturePoint(host, static_cast<float>(u), static_cast<float>(v), 0, pt)) {
          continue;
        }
        points.push_back(pt);
        trueIdepth.push_back(1. / depth);
      }
    }
    return points;
  }

  // The surface point behind host pixel (u, v) is the one seen in frame j (not occluded, inside the image).
  bool visibleIn(const ImmaturePoint &pt, unsigned int j) const
  {
    const vpColVector X = s_scene->worldPointAt(pt.u, pt.v, 0);
    const Eigen::Vector3d Xc = (*s_frames)[j]->cMw * Eigen::Vector3d(X[0], X[1], X[2]);
    const PinholeIntrinsics K = intrinsicsOf(*s_scene);
    const double u = K.fx * Xc.x() / Xc.z() + K.cx;
    const double v = K.fy * Xc.y() / Xc.z() + K.cy;
    if (!(u > 1 && v > 1 && u < kWidth - 2 && v < kHeight - 2)) {
      return false;
    }
    return std::fabs(s_scene->depthAt(u, v, j) - Xc.z()) < kVisibleRelativeDepth * Xc.z();
  }

  static vpHSlamSyntheticScene *s_scene;
  static std::vector<FramePtr> *s_frames;
};
vpHSlamSyntheticScene *SyntheticTracing::s_scene = nullptr;
std::vector<FramePtr> *SyntheticTracing::s_frames = nullptr;

double median(std::vector<double> values)
{
  if (values.empty()) {
    return 0.;
  }
  std::nth_element(values.begin(), values.begin() + static_cast<long>(values.size() / 2), values.end());
  return values[values.size() / 2];
}

TEST(ImmaturePointCreation, PatchWeightsAndThreshold)
{
  vpHSlamParameters params;
  const ImmaturePointTracer tracer(params.mapper, params.tracker);
  // A ramp with a known gradient: I = 3 u + 2 v (central differences are exact on it).
  constexpr int w = 40, h = 30;
  vpImage<float> I(h, w);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      I[v][u] = 3.f * static_cast<float>(u) + 2.f * static_cast<float>(v);
    }
  }
  Frame host;
  host.keyframeId = 7;
  host.pyramid.build(I, PinholeIntrinsics{100., 100., 19.5, 14.5}, 1, 1);
  ImmaturePoint pt;
  ASSERT_TRUE(tracer.createImmaturePoint(host, 10.f, 12.f, 1, pt));
  EXPECT_EQ(pt.hostKeyframeId, 7);
  EXPECT_EQ(pt.selectionLevel, 1);
  EXPECT_EQ(pt.lastStatus, TraceStatus::uninitialized);
  EXPECT_FALSE(std::isfinite(pt.idepthMax));
  EXPECT_FLOAT_EQ(pt.energyThreshold, static_cast<float>(hslam::kPatternSize * params.tracker.outlierEnergyPerPixel));
  const float c2 = static_cast<float>(params.tracker.gradientWeightC * params.tracker.gradientWeightC);
  for (int k = 0; k < hslam::kPatternSize; ++k) {
    EXPECT_FLOAT_EQ(pt.patch[static_cast<size_t>(k)], 3.f * (10.f + static_cast<float>(hslam::kPattern[k][0])) +
                                                          2.f * (12.f + static_cast<float>(hslam::kPattern[k][1])));
    EXPECT_NEAR(pt.patchWeight[static_cast<size_t>(k)], c2 / (c2 + 9.f + 4.f), 1e-6f);
  }
  // Too close to the border for the pattern plus interpolation room.
  EXPECT_FALSE(tracer.createImmaturePoint(host, 2.f, 12.f, 0, pt));
  EXPECT_FALSE(tracer.createImmaturePoint(host, 10.f, static_cast<float>(h - 3), 0, pt));
  EXPECT_TRUE(tracer.createImmaturePoint(host, 3.f, 3.f, 0, pt));
}

// Analytic texture on a fronto-parallel plane at depth Z; the camera translates along x by tx, so the target is
// the host shifted by f tx / Z pixels, exactly.
float planeTexture(float x, float y)
{
  return 128.f + 40.f * std::sin(0.31f * x + 0.5f * std::sin(0.07f * y)) + 30.f * std::sin(0.23f * y + 0.13f * x) +
         20.f * std::sin(0.71f * x - 0.37f * y);
}

TEST(ImmaturePointTracing, PlaneShiftRecoversInverseDepth)
{
  vpHSlamParameters params;
  const ImmaturePointTracer tracer(params.mapper, params.tracker);
  constexpr int w = 160, h = 120;
  constexpr double f = 150., Z = 2.5;
  const PinholeIntrinsics K{f, f, 79.5, 59.5};
  double txs[] = {0.02, 0.05};
  for (double tx : txs) {
    // Target camera at x = tx in the host frame: targetMhost translation is -tx.
    const float shift = static_cast<float>(f * tx / Z);
    vpImage<float> Ih(h, w), It(h, w);
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        Ih[v][u] = planeTexture(static_cast<float>(u), static_cast<float>(v));
        It[v][u] = planeTexture(static_cast<float>(u) + shift, static_cast<float>(v));
      }
    }
    Frame host, target;
    host.pyramid.build(Ih, K, 1, 1);
    target.pyramid.build(It, K, 1, 1);
    const SE3d targetMhost(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-tx, 0., 0.));
    int good = 0, contained = 0, total = 0;
    std::vector<double> errors;
    for (int v = 20; v < h - 20; v += 7) {
      for (int u = 40; u < w - 20; u += 7) {
        ImmaturePoint pt;
        ASSERT_TRUE(tracer.createImmaturePoint(host, static_cast<float>(u), static_cast<float>(v), 0, pt));
        TraceResult result;
        const TraceStatus status = tracer.trace(pt, host, target, targetMhost, 1., 0., K, &result);
        ++total;
        if (status != TraceStatus::good) {
          continue;
        }
        ++good;
        contained += (pt.idepthMin <= 1. / Z && 1. / Z <= pt.idepthMax) ? 1 : 0;
        errors.push_back(std::fabs(result.u - (static_cast<float>(u) - shift)));
        EXPECT_NEAR(result.pixelInterval, ImmaturePointTracer::projectedIntervalLength(pt, targetMhost, K), 1e-3f);
      }
    }
    ASSERT_GT(total, 50);
    EXPECT_GE(good, total * 9 / 10) << "tx " << tx;
    EXPECT_GE(contained, good * 95 / 100) << "tx " << tx;
    EXPECT_LT(median(errors), 0.1) << "tx " << tx << ": sub-pixel match error, pixels";
  }
}

// Vertical stripes seen from a camera moving vertically: the epipolar line runs along the stripes, the match is
// ambiguous (low quality), and once the interval is bounded the trace reports a bad condition.
TEST(ImmaturePointTracing, LineAlongStripesIsBadlyConditioned)
{
  vpHSlamParameters params;
  const ImmaturePointTracer tracer(params.mapper, params.tracker);
  constexpr int w = 240, h = 200; // a search longer than 10 steps always refreshes the quality
  const PinholeIntrinsics K{150., 150., 119.5, 99.5};
  vpImage<float> I(h, w);
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      I[v][u] = 128.f + 60.f * std::sin(0.6f * static_cast<float>(u));
    }
  }
  Frame host, target;
  host.pyramid.build(I, K, 1, 1);
  target.pyramid.build(I, K, 1, 1);
  const SE3d targetMhost(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0., -0.05, 0.));
  ImmaturePoint pt;
  ASSERT_TRUE(tracer.createImmaturePoint(host, 121.f, 60.f, 0, pt));
  tracer.trace(pt, host, target, targetMhost, 1., 0., K);
  EXPECT_LT(pt.quality, params.mapper.minTraceQuality);
  // Bound the interval by hand to a 10-pixel segment: the search would not be informative.
  pt.idepthMin = 0.1f;
  pt.idepthMax = 0.1f + static_cast<float>(10. / (150. * 0.05));
  pt.lastStatus = TraceStatus::good;
  EXPECT_EQ(tracer.trace(pt, host, target, targetMhost, 1., 0., K), TraceStatus::badCondition);
}

TEST_F(SyntheticTracing, IntervalContainsTruthAndShrinks)
{
  vpHSlamParameters params;
  const ImmaturePointTracer tracer(params.mapper, params.tracker);
  std::vector<double> trueIdepth;
  std::vector<ImmaturePoint> points = makePoints(tracer, trueIdepth);
  ASSERT_GT(points.size(), 300u);
  const Frame &host = *(*s_frames)[0];
  double medianWidthFirst = 0., medianWidthLast = 0.;
  for (unsigned int j = 1; j <= kLastTarget; ++j) {
    const hslam::TraceStatistics stats = tracer.traceAll(points, host, *(*s_frames)[j]);
    EXPECT_EQ(stats.total, static_cast<int>(points.size()));
    if (j < kFirstChecked) {
      continue;
    }
    int good = 0, contained = 0, highQuality = 0;
    std::vector<double> widths;
    for (size_t i = 0; i < points.size(); ++i) {
      const ImmaturePoint &pt = points[i];
      if (pt.lastStatus != TraceStatus::good || !visibleIn(pt, j)) {
        continue;
      }
      ++good;
      contained += (pt.idepthMin <= trueIdepth[i] && trueIdepth[i] <= pt.idepthMax) ? 1 : 0;
      highQuality += pt.quality > params.mapper.minTraceQuality ? 1 : 0;
      widths.push_back(static_cast<double>(pt.idepthMax - pt.idepthMin) / trueIdepth[i]);
    }
    ASSERT_GT(good, static_cast<int>(points.size()) / 3) << "frame " << j << ": too few good traces";
    EXPECT_GE(contained, kMinContainment * good) << "frame " << j << ": " << contained << " of " << good;
    EXPECT_GT(highQuality, good / 2) << "frame " << j;
    const double medianWidth = median(widths);
    if (j == kFirstChecked) {
      medianWidthFirst = medianWidth;
    }
    medianWidthLast = medianWidth;
    std::printf("frame %u: %d good+visible of %zu (good %d skip %d badcond %d oob %d outlier %d), %.1f %% contain "
                "the truth, %.1f %% quality > %.0f, median relative width %.3f\n",
                j, good, points.size(), stats.good, stats.skipped, stats.badCondition, stats.outOfBounds, stats.outlier,
                100. * contained / good, 100. * highQuality / good, params.mapper.minTraceQuality, medianWidth);
  }
  // A longer baseline gives a proportionally narrower interval (DSO: fixed pixel error over a longer line).
  EXPECT_LT(medianWidthLast, 0.6 * medianWidthFirst);
}

TEST_F(SyntheticTracing, BrightnessChangeToleratedWithMatchingTransfer)
{
  vpHSlamParameters params;
  const ImmaturePointTracer tracer(params.mapper, params.tracker);
  constexpr float kGain = 1.3f, kOffset = 5.f;
  const FramePtr brighter = makeFrame(*s_scene, kFirstChecked, kGain, kOffset);
  const Frame &host = *(*s_frames)[0];
  const SE3d targetMhost = brighter->cMw * host.cMw.inverse();
  const PinholeIntrinsics K = intrinsicsOf(*s_scene);

  std::vector<double> trueIdepth;
  std::vector<ImmaturePoint> matching = makePoints(tracer, trueIdepth);
  std::vector<ImmaturePoint> ignoring = matching;
  int goodMatching = 0, containedMatching = 0, goodIgnoring = 0, containedIgnoring = 0, visible = 0;
  for (size_t i = 0; i < matching.size(); ++i) {
    if (!visibleIn(matching[i], kFirstChecked)) {
      continue;
    }
    ++visible;
    if (tracer.trace(matching[i], host, *brighter, targetMhost, kGain, kOffset, K) == TraceStatus::good) {
      ++goodMatching;
      containedMatching += matching[i].idepthMin <= trueIdepth[i] && trueIdepth[i] <= matching[i].idepthMax;
    }
    if (tracer.trace(ignoring[i], host, *brighter, targetMhost, 1., 0., K) == TraceStatus::good) {
      ++goodIgnoring;
      containedIgnoring += ignoring[i].idepthMin <= trueIdepth[i] && trueIdepth[i] <= ignoring[i].idepthMax;
    }
  }
  ASSERT_GT(visible, 300);
  std::printf("I*%.1f+%.0f: with transfer %d good, %d contain; without %d good, %d contain (of %d)\n", kGain, kOffset,
              goodMatching, containedMatching, goodIgnoring, containedIgnoring, visible);
  EXPECT_GT(goodMatching, visible * 8 / 10);
  EXPECT_GE(containedMatching, kMinContainment * goodMatching);
  // Without the transfer, the (bright) residuals exceed the outlier threshold for many points.
  EXPECT_LT(containedIgnoring, containedMatching * 8 / 10);
}

TEST_F(SyntheticTracing, PointsLeavingTheImageAreOutOfBounds)
{
  vpHSlamParameters params;
  const ImmaturePointTracer tracer(params.mapper, params.tracker);
  std::vector<double> trueIdepth;
  std::vector<ImmaturePoint> points = makePoints(tracer, trueIdepth);
  const Frame &host = *(*s_frames)[0];
  const Frame &target = *(*s_frames)[1];
  const PinholeIntrinsics K = intrinsicsOf(*s_scene);
  // The target camera turned by 90 degrees about its y axis: every point is far outside its image.
  const double angle = M_PI / 2.;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const SE3d turned(R, Eigen::Vector3d(0.01, 0., 0.));
  int outOfBounds = 0;
  for (ImmaturePoint &pt : points) {
    TraceResult result;
    outOfBounds += tracer.trace(pt, host, target, turned, 1., 0., K, &result) == TraceStatus::outOfBounds;
    EXPECT_FLOAT_EQ(result.u, -1.f);
  }
  EXPECT_EQ(outOfBounds, static_cast<int>(points.size()));
  // Out of bounds is final: even the true pose does not bring the point back.
  const SE3d targetMhost = target.cMw * host.cMw.inverse();
  EXPECT_EQ(tracer.trace(points.front(), host, target, targetMhost, 1., 0., K), TraceStatus::outOfBounds);

  // Real motion: traced frame after frame, every point whose true projection has left the last frame is out of
  // bounds. The camera moves backwards from frame 0 to 10, so points hosted in frame 10 and traced back towards
  // frame 0 see the image expand and the ones near the border leave it.
  std::vector<double> idepths;
  std::vector<ImmaturePoint> fresh = makePoints(tracer, idepths, kBorderMargin, kLastTarget);
  const Frame &lastHost = *(*s_frames)[kLastTarget];
  for (int j = static_cast<int>(kLastTarget) - 1; j >= 0; --j) {
    tracer.traceAll(fresh, lastHost, *(*s_frames)[static_cast<size_t>(j)]);
  }
  const SE3d farMhost = host.cMw * lastHost.cMw.inverse();
  int leaving = 0, leavingOob = 0;
  for (size_t i = 0; i < fresh.size(); ++i) {
    const Eigen::Vector3d ray((fresh[i].u - K.cx) / K.fx, (fresh[i].v - K.cy) / K.fy, 1.);
    const Eigen::Vector3d p = farMhost * Eigen::Vector3d(ray / idepths[i]);
    const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
    if (u >= 0. && v >= 0. && u <= kWidth - 1. && v <= kHeight - 1.) {
      continue;
    }
    ++leaving;
    leavingOob += fresh[i].lastStatus == TraceStatus::outOfBounds;
  }
  std::printf("%d of %zu points left the image between frames %u and 0\n", leaving, fresh.size(), kLastTarget);
  ASSERT_GT(leaving, 0);
  EXPECT_EQ(leavingOob, leaving);
}
} // namespace
