// The metric frame from tag sightings (map/MetricFrame.h): the robust similarity fit against a known one, with the
// detector's noise, one wrong sighting, and the cases where the scale is not observable.
#include "map/MetricFrame.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace hslam;

namespace
{
constexpr double kDegToRad = M_PI / 180.;

//! The true similarity from SLAM world to the tag's frame: scale 0.37 m per map unit, a turn, an offset.
Sim3d trueSimilarity()
{
  const Eigen::Quaterniond R(Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -1., 0.2).normalized()));
  return Sim3d(R, Eigen::Vector3d(0.4, -0.2, 1.1), 0.37);
}

/*!
  \e n views of the tag from cameras on an arc 1.5-2.5 m in front of it (tag frame: z out of the tag, towards the
  cameras), \e baseline metres wide; the detector's noise: 0.3 % of the range in position, \e rotationNoiseDeg.
*/
std::vector<TagView> makeViews(int n, double baseline, double rotationNoiseDeg, unsigned int seed)
{
  std::mt19937 rng(seed);
  std::normal_distribution<double> unit(0., 1.);
  const Sim3d mSw = trueSimilarity();
  const Sim3d wSm = mSw.inverse();
  std::vector<TagView> views;
  for (int i = 0; i < n; ++i) {
    const double a = n > 1 ? static_cast<double>(i) / (n - 1) - 0.5 : 0.;
    const Eigen::Vector3d centre =
        Eigen::Vector3d(0.1, -0.1, 2.) + baseline * Eigen::Vector3d(a, 0.2 * std::sin(3. * a), 0.5 * std::cos(4. * a));
    // Camera looking at the tag's centre: z towards -centre.
    const Eigen::Vector3d z = (-centre).normalized();
    const Eigen::Vector3d x = Eigen::Vector3d::UnitY().cross(z).normalized();
    Eigen::Matrix3d tRc;
    tRc << x, z.cross(x), z;
    const SE3d tMc(tRc, centre);
    // SLAM pose: x_w = wSm x_t.
    const Eigen::Matrix3d wRc = wSm.rotationMatrix() * tRc;
    const SE3d wMc(wRc, wSm * centre);
    SE3d cMt = tMc.inverse();
    const double range = centre.norm();
    Eigen::Matrix<double, 6, 1> noise;
    noise << 0.003 * range * unit(rng), 0.003 * range * unit(rng), 0.003 * range * unit(rng),
        rotationNoiseDeg * kDegToRad * unit(rng), rotationNoiseDeg * kDegToRad * unit(rng),
        rotationNoiseDeg * kDegToRad * unit(rng);
    cMt = SE3d::exp(noise) * cMt;
    views.push_back(TagView{wMc, cMt});
  }
  return views;
}

//! Scale, rotation, and position error where the cameras were (2 m in front of the tag), which is what a user of the
//! metric poses sees (the SLAM world's origin may be anywhere).
void expectNearTruth(const MetricFit &fit, double scaleShare, double metres, double degrees)
{
  const Sim3d truth = trueSimilarity();
  EXPECT_NEAR(fit.scale / truth.scale(), 1., scaleShare);
  const Eigen::Vector3d whereCamerasWere = truth.inverse() * Eigen::Vector3d(0.1, -0.1, 2.);
  EXPECT_LT((fit.mSw * whereCamerasWere - truth * whereCamerasWere).norm(), metres);
  EXPECT_LT(fit.mSw.unitQuaternion().angularDistance(truth.unitQuaternion()) / kDegToRad, degrees);
}
} // namespace

TEST(MetricFrame, FitsTheTrueSimilarityFromNoisySightings)
{
  const vpHSlamParameters::TagFrame options;
  const MetricFit fit = fitMetricFrame(makeViews(20, 1.0, 1., 1), true, options);
  EXPECT_TRUE(fit.metric) << "scale uncertainty " << fit.scaleUncertainty;
  EXPECT_EQ(fit.kept, 20u);
  EXPECT_LT(fit.scaleUncertainty, 0.01);
  expectNearTruth(fit, 0.01, 0.01, 0.5);
}

TEST(MetricFrame, OneWrongSightingIsRefused)
{
  const vpHSlamParameters::TagFrame options;
  for (int kind = 0; kind < 2; ++kind) {
    std::vector<TagView> views = makeViews(12, 1.0, 1., 2);
    TagView &bad = views[5];
    if (kind == 0) {
      // The ambiguous pose of a small tag: flipped about the tag's x axis, same centre seen.
      bad.cMt =
          bad.cMt * SE3d(Eigen::Matrix3d(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitX())), Eigen::Vector3d::Zero());
    } else {
      // Another tag with the same id (or a bad corner): 25 cm off.
      bad.cMt.translation() += Eigen::Vector3d(0.25, 0., 0.);
    }
    const MetricFit fit = fitMetricFrame(views, true, options);
    EXPECT_FALSE(fit.inlier[5]) << "kind " << kind;
    EXPECT_EQ(fit.kept, 11u) << "kind " << kind;
    EXPECT_TRUE(fit.metric) << "kind " << kind;
    expectNearTruth(fit, 0.01, 0.01, 0.5);
  }
}

TEST(MetricFrame, NotMetricWhereTheScaleIsNotObservable)
{
  const vpHSlamParameters::TagFrame options;
  // Too few sightings.
  EXPECT_FALSE(fitMetricFrame(makeViews(2, 1.0, 1., 3), true, options).metric);
  EXPECT_FALSE(fitMetricFrame(makeViews(1, 1.0, 1., 3), true, options).metric);
  EXPECT_FALSE(fitMetricFrame({}, true, options).metric);
  // The camera only turns: every sighting from (almost) the same place.
  EXPECT_FALSE(fitMetricFrame(makeViews(15, 0.002, 1., 4), true, options).metric);
  // Three views close together: a fit, but not trusted yet; more views farther apart make it metric.
  const MetricFit few = fitMetricFrame(makeViews(3, 0.1, 1., 5), true, options);
  EXPECT_FALSE(few.metric) << few.scaleUncertainty;
  EXPECT_TRUE(fitMetricFrame(makeViews(15, 1.0, 1., 5), true, options).metric);
}

TEST(MetricFrame, WithoutAnIdOnlyTheScaleIsApplied)
{
  const vpHSlamParameters::TagFrame options;
  const MetricFit fit = fitMetricFrame(makeViews(20, 1.0, 1., 6), false, options);
  EXPECT_TRUE(fit.metric);
  EXPECT_FALSE(fit.tagFrame);
  EXPECT_NEAR(fit.scale / trueSimilarity().scale(), 1., 0.01);
  EXPECT_NEAR(fit.mSw.scale(), fit.scale, 1e-12);
  EXPECT_LT(fit.mSw.translation().norm(), 1e-12);
  EXPECT_LT(fit.mSw.unitQuaternion().angularDistance(Eigen::Quaterniond::Identity()), 1e-12);
}

TEST(MetricFrame, RefitReadsTheKeyframesCurrentPosesOfTheCurrentSegment)
{
  vpHSlamParameters::TagFrame options;
  MetricFrame frame(vpHSlamTag("tag36h11", 0.16, 0), options);
  const std::vector<TagView> views = makeViews(10, 1.0, 1., 7);
  std::vector<SE3d> poses;
  for (size_t i = 0; i < views.size(); ++i) {
    TagSighting s;
    s.id = 0;
    s.cMt = views[i].cMt;
    frame.addSightings(static_cast<int>(i), 0, {s});
    poses.push_back(views[i].wMc);
  }
  EXPECT_EQ(frame.sightingCount(), 10u);
  EXPECT_FALSE(frame.current().metric); // nothing fitted yet
  frame.refit([&](int id, SE3d &wMc) {
    wMc = poses[static_cast<size_t>(id)];
    return true;
  });
  ASSERT_TRUE(frame.current().metric);
  expectNearTruth(frame.current(), 0.01, 0.01, 0.5);
  // The map was scaled by 2 (a loop correction, say): the fitted scale follows.
  for (SE3d &p : poses) {
    p.translation() *= 2.;
  }
  frame.refit([&](int id, SE3d &wMc) {
    wMc = poses[static_cast<size_t>(id)];
    return true;
  });
  EXPECT_NEAR(frame.current().scale / (0.5 * trueSimilarity().scale()), 1., 0.01);
  // A loop correction divides the map around the keyframes by 2 again: their depth measurements (none here) and the
  // fit follow; rescaling keyframes that saw nothing changes nothing.
  frame.rescaleKeyframes({1000}, {2.});
  EXPECT_TRUE(frame.current().metric);
  // Tracking is lost: the new segment has its own scale, so the old fit no longer applies, even at the next refit
  // (its sightings belong to the old segment); one sighting in the new segment is not enough.
  frame.startSegment(1);
  EXPECT_FALSE(frame.current().metric);
  frame.refit([&](int id, SE3d &wMc) {
    wMc = poses[static_cast<size_t>(id)];
    return true;
  });
  EXPECT_FALSE(frame.current().metric);
  EXPECT_FALSE(appliesTo(frame.current(), 0));
  frame.clear();
  EXPECT_EQ(frame.sightingCount(), 0u);
}

TEST(MetricFrame, TheTagsDepthInTheMapFixesTheScaleAndFollowsALoopCorrection)
{
  // The camera hardly moves (2 mm): only the map's points on the tag can tell the scale. Their depth against the tag
  // plane's metric depth is measured at refit; a loop correction that divides the map by 2 must carry it along.
  vpHSlamParameters::TagFrame options;
  vpCameraParameters K;
  K.initPersProjWithoutDistortion(500., 500., 320., 240.);
  MetricFrame frame;
  frame.setTag(vpHSlamTag("tag36h11", 0.16, 0), options, K);
  const std::vector<TagView> views = makeViews(8, 0.002, 0., 10);
  const Sim3d wSm = trueSimilarity().inverse();
  std::vector<SE3d> poses;
  for (size_t i = 0; i < views.size(); ++i) {
    TagSighting s;
    s.id = 0;
    s.cMt = views[i].cMt;
    for (int k = 0; k < 4; ++k) { // the tag's corners, 8 cm from its centre
      const Eigen::Vector3d X = s.cMt * Eigen::Vector3d(k == 1 || k == 2 ? 0.08 : -0.08, k >= 2 ? 0.08 : -0.08, 0.);
      s.corners[static_cast<size_t>(k)] = Eigen::Vector2d(320. + 500. * X.x() / X.z(), 240. + 500. * X.y() / X.z());
    }
    frame.addSightings(static_cast<int>(i), 0, {s});
    poses.push_back(views[i].wMc);
  }
  std::vector<Eigen::Vector3d> points; // on the tag, in the map
  for (int u = -2; u <= 2; ++u) {
    for (int v = -2; v <= 2; ++v) {
      points.push_back(wSm * Eigen::Vector3d(0.025 * u, 0.025 * v, 0.));
    }
  }
  double mapScale = 1.; // the map's distances are divided by this
  const auto pose = [&](int id, SE3d &wMc) {
    wMc = poses[static_cast<size_t>(id)];
    wMc.translation() /= mapScale;
    return true;
  };
  frame.refit(pose); // no points yet: the positions alone do not tell the scale
  EXPECT_FALSE(frame.current().metric);
  frame.refit(pose, [&](std::vector<Eigen::Vector3d> &out) { out = points; });
  ASSERT_TRUE(frame.current().metric) << frame.current().scaleUncertainty;
  EXPECT_NEAR(frame.current().depthScale / trueSimilarity().scale(), 1., 0.003); // the poses carry 0.3 % noise
  EXPECT_NEAR(frame.current().scale / trueSimilarity().scale(), 1., 0.003);
  // The map divided by 2 around every keyframe (no point in view any more): with the stored depths rescaled, the
  // scale is twice the metres per unit.
  mapScale = 2.;
  std::vector<int> ids;
  for (size_t i = 0; i < views.size(); ++i) {
    ids.push_back(static_cast<int>(i));
  }
  frame.rescaleKeyframes(ids, std::vector<double>(ids.size(), 2.));
  frame.refit(pose);
  ASSERT_TRUE(frame.current().metric);
  EXPECT_NEAR(frame.current().scale / (2. * trueSimilarity().scale()), 1., 0.003);
}

TEST(MetricFrame, ATagSeenAgainAsksForACorrectionAtTheFirstAndThirdKeyframeOfTheRevisit)
{
  vpHSlamParameters::TagFrame options;
  MetricFrame frame(vpHSlamTag("tag36h11", 0.16, 0), options);
  TagSighting s;
  s.id = 0;
  const auto see = [&](int keyframe) { frame.addSightings(keyframe, 0, {s}); };
  for (int k : {0, 1, 2}) { // the first visit: nothing to correct
    see(k);
    EXPECT_FALSE(frame.seenAgain(k)) << k;
  }
  see(5); // the camera looked away for two keyframes: the same visit
  EXPECT_FALSE(frame.seenAgain(5));
  const int back = 5 + MetricFrame::kRevisitKeyframes; // away long enough: a revisit
  for (int k = back; k < back + 5; ++k) {
    see(k);
    EXPECT_EQ(frame.seenAgain(k), k == back || k == back + 2) << k;
  }
  EXPECT_FALSE(frame.seenAgain(back + 10)); // a keyframe that saw nothing
  // Another tag seen for the first time is no revisit; sightings of another segment do not count.
  s.id = 1;
  see(back + 30);
  EXPECT_FALSE(frame.seenAgain(back + 30));
  frame.startSegment(1);
  s.id = 0;
  frame.addSightings(back + 60, 1, {s});
  EXPECT_FALSE(frame.seenAgain(back + 60));
  EXPECT_EQ(frame.segmentSightings().size(), 1u);
}
