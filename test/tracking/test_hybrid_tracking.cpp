// Hybrid tracking on the synthetic scene with exact depths: corner selection, the indirect step (ORB matches of
// reference corners into a new frame, pose-only optimisation), the joint photometric + geometric optimisation
// (recovered pose, Jacobians against numeric differences, indirect-only ablation) and shared point selection.
#include "HSlamTestData.h"
#include "TrackingTestUtils.h"

#include "features/CornerDetector.h"
#include "features/PointDescriptors.h"
#include "features/SharedPointSelector.h"
#include "tracking/HybridTracker.h"
#include "tracking/PoseOnlyOptimizer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

using namespace hslam;

namespace
{
constexpr unsigned int kWidth = 640;
constexpr unsigned int kHeight = 480;
constexpr unsigned int kFrames = 100;

#define REQUIRE_TEXTURES()                                                                                             \
  if (hslam_test::vispImagesDir().empty()) {                                                                           \
    GTEST_SKIP() << "visp-images-data not installed (/usr/share/visp-images-data/ViSP-images)";                        \
  }

class HybridTrackingTest : public ::testing::Test
{
protected:
  void SetUp() override
  {
    if (hslam_test::vispImagesDir().empty()) {
      return;
    }
    scene.configure(kWidth, kHeight, kFrames, 30.0, 1);
    hslam_test::makeFrame(scene, 0, params.tracker, reference);
    points = hslam_test::selectPoints(scene, 0, reference, 2000);
    K = hslam_test::sceneIntrinsics(scene);
    // Reference features: FAST corners of frame 0 with their exact 3D position and descriptor.
    features = hslam_test::referenceFeatures(scene, 0, reference);
  }

  vpHSlamParameters params;
  vpHSlamSyntheticScene scene;
  Frame reference;
  std::vector<CoarseTrackerPoint> points;
  std::vector<ReferenceFeature> features;
  PinholeIntrinsics K;
};

//! A geometric term of \e n points seen from \e truth, pixels disturbed by \e noise (standard deviation, pixels).
GeometricTerm syntheticTerm(const SE3d &truth, const PinholeIntrinsics &K, int n, double noise, unsigned seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-1.5, 1.5), depth(2., 6.);
  std::normal_distribution<double> pixel(0., noise);
  GeometricTerm term;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d X(xy(rng), xy(rng), depth(rng));
    const Eigen::Vector3d c = truth * X;
    term.Xref.push_back(X);
    term.uv.emplace_back(K.fx * c.x() / c.z() + K.cx + pixel(rng), K.fy * c.y() / c.z() + K.cy + pixel(rng));
  }
  term.inliers = n;
  term.sigma2Px = std::max(noise * noise, 0.25);
  return term;
}

//! A 500 px pinhole camera centred on a 640x480 image.
PinholeIntrinsics squarePixelCamera()
{
  PinholeIntrinsics K;
  K.fx = K.fy = 500.;
  K.cx = 320.;
  K.cy = 240.;
  return K;
}

//! The pose the geometry-only tests recover.
SE3d geometryTestPose()
{
  return SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.2, 0.1, -0.1, 0.05, 0.02, -0.03).finished());
}

//! Gauss-Newton on the geometric energy alone (no photometric term, no damping), 10 steps from \e pose.
SE3d minimiseGeometricEnergy(const GeometricTerm &term, const PinholeIntrinsics &K, SE3d pose)
{
  for (int it = 0; it < 10; ++it) {
    Eigen::Matrix<double, 8, 8> H = Eigen::Matrix<double, 8, 8>::Zero();
    Eigen::Matrix<double, 8, 1> b = Eigen::Matrix<double, 8, 1>::Zero();
    CoarseTracker::geometricEnergy(term, K, pose, &H, &b);
    pose = SE3d::exp(H.topLeftCorner<6, 6>().ldlt().solve(-b.head<6>())) * pose;
  }
  return pose;
}
} // namespace

TEST(HybridTrackingMath, geometricWeightFollowsEquation4)
{
  // K = 5 exp(-2 l) / (1 + exp((30 - N_g) / 4)), l counted from the coarsest level.
  EXPECT_NEAR(geometricWeight(0, 30), 2.5, 1e-12);
  EXPECT_NEAR(geometricWeight(2, 30), 2.5 * std::exp(-4.), 1e-12);
  EXPECT_NEAR(geometricWeight(0, 10), 5. / (1. + std::exp(5.)), 1e-12);
  EXPECT_GT(geometricWeight(0, 100), 4.99);
}

TEST(HybridTrackingMath, geometricJacobianMatchesNumericDifferences)
{
  PinholeIntrinsics K;
  K.fx = 500.;
  K.fy = 480.;
  K.cx = 320.;
  K.cy = 240.;
  const SE3d truth = SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.1, -0.05, 0.2, 0.03, -0.02, 0.05).finished());
  // Noise of 3 pixels puts some residuals past the Huber threshold: both branches are checked.
  GeometricTerm term = syntheticTerm(truth, K, 60, 3., 7);
  const SE3d at =
      SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.01, 0.01, -0.01, 0.002, 0.001, -0.003).finished()) * truth;
  for (bool weighted : {false, true}) {
    if (weighted) { // paper eq. 3 weights in (0, 1]
      for (size_t i = 0; i < term.Xref.size(); ++i) {
        term.weights.push_back(0.1 + 0.9 * static_cast<double>(i % 7) / 6.);
      }
    }
    Eigen::Matrix<double, 8, 8> H = Eigen::Matrix<double, 8, 8>::Zero();
    Eigen::Matrix<double, 8, 1> b = Eigen::Matrix<double, 8, 1>::Zero();
    CoarseTracker::geometricEnergy(term, K, at, &H, &b);
    const double eps = 1e-6;
    for (int i = 0; i < 6; ++i) {
      Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
      d[i] = eps;
      const double ep = CoarseTracker::geometricEnergy(term, K, SE3d::exp(d) * at);
      const double em = CoarseTracker::geometricEnergy(term, K, SE3d::exp(-d) * at);
      const double numeric = (ep - em) / (2. * eps);
      // Energy = sum of rho(r^2): its gradient is 2 J^T W r = 2 b.
      EXPECT_NEAR(2. * b[i], numeric, 1e-4 * std::max(1., std::fabs(numeric)))
          << "twist component " << i << (weighted ? ", weighted" : "");
    }
    EXPECT_TRUE(H.bottomRows<2>().isZero()) << "the geometric term must not touch the affine parameters";
    const double det = H.topLeftCorner<6, 6>().determinant();
    EXPECT_GT(det, 0.);
  }
}

TEST(HybridTrackingMath, depthWeightsDampenPointsOfUncertainDepth)
{
  // Paper eq. 3: 80 exact matches and 20 whose points are 1.5 px off (inside the Huber threshold, so they bias an
  // unweighted solution); weighted as points of 1000x the depth variance, they hardly move the pose.
  const PinholeIntrinsics K = squarePixelCamera();
  const SE3d truth = geometryTestPose();
  GeometricTerm term = syntheticTerm(truth, K, 100, 0., 13);
  for (size_t i = 80; i < 100; ++i) {
    term.uv[i] += Eigen::Vector2d(1.5, 0.);
  }
  auto solve = [&](const GeometricTerm &t) {
    return (minimiseGeometricEnergy(t, K, truth) * truth.inverse()).log().norm();
  };
  const double unweighted = solve(term);
  term.weights.assign(100, 1.);
  std::fill(term.weights.begin() + 80, term.weights.end(), 1e-3);
  const double weighted = solve(term);
  EXPECT_GT(unweighted, 1e-3);
  EXPECT_LT(weighted, 0.01 * unweighted);
  // A weight scales its residual's energy.
  GeometricTerm one = syntheticTerm(truth, K, 1, 0., 17);
  one.uv[0] += Eigen::Vector2d(1., 1.);
  const double plain = CoarseTracker::geometricEnergy(one, K, truth);
  one.weights = {0.25};
  EXPECT_NEAR(CoarseTracker::geometricEnergy(one, K, truth), 0.25 * plain, 1e-12);
}

TEST_F(HybridTrackingTest, cornersAreSpreadAndKeepTheirDistance)
{
  REQUIRE_TEXTURES();
  CornerOptions options;
  options.maxCorners = 300;
  options.minDistance = 6.;
  options.border = 20;
  std::vector<cv::Point2f> corners;
  std::vector<float> responses;
  detectCorners(reference.raw, options, corners, &responses);
  ASSERT_GT(corners.size(), 100u);
  EXPECT_LE(corners.size(), 300u);
  for (size_t i = 0; i < corners.size(); ++i) {
    EXPECT_GE(corners[i].x, 20.f);
    EXPECT_GE(corners[i].y, 20.f);
    EXPECT_LE(corners[i].x, kWidth - 21.f);
    EXPECT_LE(corners[i].y, kHeight - 21.f);
    for (size_t j = i + 1; j < corners.size(); ++j) {
      const double d = std::hypot(corners[i].x - corners[j].x, corners[i].y - corners[j].y);
      ASSERT_GE(d, 6.) << "corners " << i << " and " << j;
    }
  }
  // Spread: no quarter of the image holds more than 60 % of the corners.
  int quarter[4] = {0, 0, 0, 0};
  for (const cv::Point2f &c : corners) {
    ++quarter[(c.x < kWidth / 2 ? 0 : 1) + (c.y < kHeight / 2 ? 0 : 2)];
  }
  for (int q : quarter) {
    EXPECT_LT(q, static_cast<int>(0.6 * corners.size()));
  }
  std::vector<cv::Point2f> again;
  detectCorners(reference.raw, options, again);
  EXPECT_EQ(again, corners) << "detection must be deterministic";
}

TEST_F(HybridTrackingTest, strongCornersFirstGiveTheCornersOfOneDetection)
{
  // Four images: the scene (corners of every strength), a high-contrast noise texture (the budget is filled at the
  // strictest threshold), the same texture at a tenth of its contrast (no corner scores 10: the last fallback), and
  // strong texture in the left quarter only, faint elsewhere (the strong corners fill the budget only once the
  // first pass's per-cell caps are lifted, which must not count: the weak cells have their share at threshold 7).
  vpImage<unsigned char> noisy(kHeight, kWidth), faint(kHeight, kWidth), patchy(kHeight, kWidth);
  unsigned int state = 12345u;
  for (unsigned int i = 0; i < noisy.getSize(); ++i) {
    state = state * 1664525u + 1013904223u;
    noisy.bitmap[i] = static_cast<unsigned char>(state >> 24);
    faint.bitmap[i] = static_cast<unsigned char>(120 + noisy.bitmap[i] / 10);
    patchy.bitmap[i] = i % kWidth < kWidth / 4 ? noisy.bitmap[i] : faint.bitmap[i];
  }
  const vpImage<unsigned char> *images[] = {&reference.raw, &noisy, &faint, &patchy};
  for (const vpImage<unsigned char> *image : images) {
    for (int threshold : {5, 7, 12}) {
      for (int budget : {10, 60, 250, 1000, 20000}) {
        CornerOptions options;
        options.threshold = threshold;
        options.maxCorners = budget;
        options.border = kOrbBorderPx + 1;
        std::vector<cv::Point2f> ladder, single;
        std::vector<float> ladderScores, singleScores;
        detectCorners(*image, options, ladder, &ladderScores);
        // With a hint from another image (every start of the ladder, stale or not): the same corners again.
        for (int start : {0, 10, 15, 20, 40}) {
          CornerThresholdHint hint;
          hint.threshold = start;
          std::vector<cv::Point2f> hinted;
          detectCorners(*image, options, hinted, nullptr, &hint);
          EXPECT_EQ(hinted, ladder) << "hint " << start << ", threshold " << threshold << ", budget " << budget;
        }
        options.strongFirst = false;
        detectCorners(*image, options, single, &singleScores);
        ASSERT_FALSE(single.empty());
        EXPECT_EQ(ladder, single) << "threshold " << threshold << ", budget " << budget;
        EXPECT_EQ(ladderScores, singleScores) << "threshold " << threshold << ", budget " << budget;
      }
    }
  }
}

TEST_F(HybridTrackingTest, cornersComeStrongestFirstThenByRowThenColumn)
{
  // No cap, no distance rule, an unbounded budget: the output is FAST's whole sorted list.
  CornerOptions options;
  options.maxCorners = 1000000;
  options.minDistance = 0.;
  options.cellShareFactor = 1.; // with this budget, a cap above any 40x40 cell's pixel count
  options.border = kOrbBorderPx + 1;
  std::vector<cv::Point2f> corners;
  std::vector<float> scores;
  detectCorners(reference.raw, options, corners, &scores);
  ASSERT_GT(corners.size(), 1000u);
  size_t ties = 0;
  for (size_t i = 1; i < corners.size(); ++i) {
    ASSERT_GE(scores[i - 1], scores[i]) << i;
    if (scores[i - 1] == scores[i]) {
      ++ties;
      const bool ordered =
          corners[i - 1].y < corners[i].y || (corners[i - 1].y == corners[i].y && corners[i - 1].x < corners[i].x);
      ASSERT_TRUE(ordered) << i;
    }
  }
  EXPECT_GT(ties, 100u) << "the tie rule was not exercised";
}

TEST_F(HybridTrackingTest, sharedSelectionPutsCornersFirstWithinTheirShare)
{
  REQUIRE_TEXTURES();
  vpHSlamParameters::Features f = params.features;
  f.cornerShare = 0.4;
  SharedPointSelector shared(f, true);
  std::vector<SelectedPixel> selected;
  std::vector<bool> isCorner;
  shared.select(reference.raw, reference.pyramid, 1000, 3, selected, isCorner);
  ASSERT_EQ(selected.size(), isCorner.size());
  ASSERT_GT(shared.lastCorners(), 100);
  EXPECT_LE(shared.lastCorners(), 400);
  for (int i = 0; i < shared.lastCorners(); ++i) {
    EXPECT_TRUE(isCorner[static_cast<size_t>(i)]);
  }
  // Corners come on top of the gradient selection (its whole budget), less a gradient pixel on a corner's pixel.
  PixelSelector gradientsOnly(f);
  std::vector<SelectedPixel> gradients;
  gradientsOnly.select(reference.pyramid, 1000, 3, gradients);
  EXPECT_LE(selected.size(), static_cast<size_t>(shared.lastCorners()) + gradients.size());
  EXPECT_GT(selected.size(), static_cast<size_t>(shared.lastCorners()) + gradients.size() * 9 / 10);
  for (size_t i = 0; i < selected.size(); ++i) {
    for (size_t j = static_cast<size_t>(shared.lastCorners()); j < selected.size() && i < j; ++j) {
      if (selected[i].u == selected[j].u && selected[i].v == selected[j].v) {
        ADD_FAILURE() << "pixel (" << selected[i].u << ", " << selected[i].v << ") selected twice";
      }
    }
  }
  // Descriptors off (direct tracking): exactly the gradient selector's output.
  SharedPointSelector direct(f, false);
  PixelSelector plain(f);
  std::vector<SelectedPixel> a, b;
  std::vector<bool> flags;
  direct.select(reference.raw, reference.pyramid, 1000, 3, a, flags);
  plain.select(reference.pyramid, 1000, 3, b);
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].u, b[i].u);
    EXPECT_EQ(a[i].v, b[i].v);
    EXPECT_FALSE(flags[i]);
  }
}

TEST_F(HybridTrackingTest, sharedSelectionTakesOneKindWhenAsked)
{
  // The first keyframe's initial points are gradient pixels only, its corners come next (LocalMapper::initialize).
  REQUIRE_TEXTURES();
  SharedPointSelector shared(params.features, true);
  std::vector<SelectedPixel> both, corners, gradients, plain;
  std::vector<bool> bothFlags, cornerFlags, gradientFlags;
  shared.select(reference.raw, reference.pyramid, 1000, 3, both, bothFlags);
  const int cornerCount = shared.lastCorners();
  ASSERT_GT(cornerCount, 50);
  shared.select(reference.raw, reference.pyramid, 1000, 3, corners, cornerFlags, SharedPointSelector::cornersOnly);
  ASSERT_EQ(corners.size(), static_cast<size_t>(cornerCount)) << "the corners of the full selection, no more";
  for (size_t i = 0; i < corners.size(); ++i) {
    EXPECT_EQ(corners[i].u, both[i].u);
    EXPECT_EQ(corners[i].v, both[i].v);
    EXPECT_TRUE(cornerFlags[i]);
  }
  // Fresh selectors: the gradient selector adapts its cell size from one call to the next.
  SharedPointSelector(params.features, true)
      .select(reference.raw, reference.pyramid, 1000, 3, gradients, gradientFlags, SharedPointSelector::gradientsOnly);
  PixelSelector(params.features).select(reference.pyramid, 1000, 3, plain);
  ASSERT_EQ(gradients.size(), plain.size());
  for (size_t i = 0; i < gradients.size(); ++i) {
    EXPECT_EQ(gradients[i].u, plain[i].u);
    EXPECT_EQ(gradients[i].v, plain[i].v);
    EXPECT_FALSE(gradientFlags[i]);
  }
  // Descriptors off: there are no corners to take.
  SharedPointSelector direct(params.features, false);
  direct.select(reference.raw, reference.pyramid, 1000, 3, corners, cornerFlags, SharedPointSelector::cornersOnly);
  EXPECT_TRUE(corners.empty());
  EXPECT_TRUE(cornerFlags.empty());
}

TEST_F(HybridTrackingTest, indirectStepMatchesAndRecoversThePose)
{
  REQUIRE_TEXTURES();
  ASSERT_GT(features.size(), 200u);
  HybridTracker hybrid(params, K, static_cast<int>(kWidth), static_cast<int>(kHeight));
  for (unsigned int target : {5u, 10u}) {
    Frame frame;
    hslam_test::makeFrame(scene, target, params.tracker, frame);
    hybrid.extract(frame.raw);
    ASSERT_GT(hybrid.keypoints().size(), 200u);
    const SE3d truth = hslam_test::groundTruthNewMref(scene, 0, target);
    // Predicted pose off by ~ 2 cm and ~ 0.6 degree (a constant-velocity guess).
    const SE3d predicted =
        SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.02, -0.01, 0.01, 0.01, 0.005, -0.004).finished()) * truth;
    IndirectStepResult out;
    ASSERT_TRUE(hybrid.indirectStep(features, predicted, out)) << "frame " << target;
    EXPECT_GT(out.matches, 100) << "frame " << target;
    EXPECT_GT(static_cast<double>(out.inliers) / out.matches, 0.8) << "inlier ratio, frame " << target;
    double dt = 0., dr = 0.;
    hslam_test::poseError(out.newMref, truth, dt, dr);
    EXPECT_LT(dt, 5e-3) << "frame " << target;
    EXPECT_LT(dr, 0.1) << "frame " << target;
    EXPECT_EQ(out.term.Xref.size(), static_cast<size_t>(out.inliers));
    EXPECT_GT(out.term.sigma2Px, 0.);
    EXPECT_LT(out.term.sigma2Px, 2.);
  }
}

TEST_F(HybridTrackingTest, indirectStepWeighsMatchesByDepthInformation)
{
  REQUIRE_TEXTURES();
  Frame frame10;
  hslam_test::makeFrame(scene, 10, params.tracker, frame10);
  std::vector<ReferenceFeature> described = features;
  for (size_t i = 0; i < described.size(); ++i) {
    described[i].idepthVar = 1e-4 * static_cast<double>(1 + i % 4); // information 1, 1/2, 1/3, 1/4 of the best
  }
  vpHSlamParameters weighting = params;
  weighting.tracking.geometricDepthWeights = true;
  // The indirect step from the true pose of frame 10 with the given settings.
  auto stepWith = [&](const vpHSlamParameters &settings) {
    HybridTracker tracker(settings, K, static_cast<int>(kWidth), static_cast<int>(kHeight));
    tracker.extract(frame10.raw);
    IndirectStepResult out;
    EXPECT_TRUE(tracker.indirectStep(described, hslam_test::groundTruthNewMref(scene, 0, 10), out));
    return out;
  };
  const IndirectStepResult plain = stepWith(params);
  EXPECT_TRUE(plain.term.weights.empty());
  EXPECT_EQ(plain.term.count, 0.);

  const IndirectStepResult weighted = stepWith(weighting);
  ASSERT_EQ(weighted.term.weights.size(), weighted.term.Xref.size());
  ASSERT_FALSE(weighted.term.weights.empty());
  const auto range = std::minmax_element(weighted.term.weights.begin(), weighted.term.weights.end());
  EXPECT_DOUBLE_EQ(*range.second, 1.);
  EXPECT_NEAR(*range.first, 0.25, 1e-9);
  EXPECT_NEAR(weighted.term.count, std::accumulate(weighted.term.weights.begin(), weighted.term.weights.end(), 0.),
              1e-9);
  EXPECT_LT(weighted.term.count, static_cast<double>(weighted.term.Xref.size()));
  EXPECT_GT(weighted.term.sigma2Px, 0.);

  // An inlier without a variance (0: unknown, every second feature here) leaves every weight at 1.
  for (size_t i = 0; i < described.size(); i += 2) {
    described[i].idepthVar = 0.;
  }
  const IndirectStepResult unknown = stepWith(weighting);
  EXPECT_TRUE(unknown.term.weights.empty());
  EXPECT_EQ(unknown.term.count, 0.);
}

TEST_F(HybridTrackingTest, jointOptimisationRecoversAPerturbedPose)
{
  REQUIRE_TEXTURES();
  const unsigned int target = 10;
  Frame frame;
  hslam_test::makeFrame(scene, target, params.tracker, frame);
  const SE3d truth = hslam_test::groundTruthNewMref(scene, 0, target);
  HybridTracker hybrid(params, K, static_cast<int>(kWidth), static_cast<int>(kHeight));
  hybrid.extract(frame.raw);
  const SE3d start =
      SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.03, -0.02, 0.02, 0.01, -0.01, 0.008).finished()) * truth;
  IndirectStepResult indirect;
  ASSERT_TRUE(hybrid.indirectStep(features, start, indirect));
  for (bool geometryOnly : {false, true}) {
    CoarseTracker tracker(params.tracker);
    tracker.setReference(reference, points);
    indirect.term.poseFromGeometryOnly = geometryOnly;
    tracker.setGeometricTerm(&indirect.term);
    SE3d newMref = start;
    AffineBrightness affine;
    CoarseTrackingResult result;
    ASSERT_TRUE(tracker.track(frame, newMref, affine, result)) << coarseTrackingStatusName(result.status);
    double dt = 0., dr = 0.;
    hslam_test::poseError(newMref, truth, dt, dr);
    EXPECT_LT(dt, geometryOnly ? 5e-3 : 2e-3) << (geometryOnly ? "indirect" : "hybrid");
    EXPECT_LT(dr, geometryOnly ? 0.1 : 0.05) << (geometryOnly ? "indirect" : "hybrid");
    // K at the finest level, counted from the coarsest level used (see geometricWeight()).
    EXPECT_NEAR(result.geometricWeight, geometricWeight(tracker.numLevels() - 1, indirect.term.inliers), 1e-12);
  }
}

TEST(HybridTrackingMath, geometryOnlyTermRecoversPoseWithoutPhotometricHelp)
{
  // Pure geometry: the geometric energy alone, minimised by Gauss-Newton, returns to the truth.
  const PinholeIntrinsics K = squarePixelCamera();
  const SE3d truth = geometryTestPose();
  const GeometricTerm term = syntheticTerm(truth, K, 80, 0.5, 11);
  const SE3d pose = minimiseGeometricEnergy(
      term, K, SE3d::exp((Eigen::Matrix<double, 6, 1>() << 0.05, -0.05, 0.05, 0.02, 0.02, 0.02).finished()) * truth);
  EXPECT_LT((pose.translation() - truth.translation()).norm(), 0.01);
  EXPECT_LT((pose * truth.inverse()).log().tail<3>().norm(), 1e-3);
}
