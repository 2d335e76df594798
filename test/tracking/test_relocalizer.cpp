// Relocalisation on an exact synthetic scene: three places, a lost frame near one of them; the keyframe database
// proposes that place first, BoW matching + PnP RANSAC + pose-only refinement recover the pose. A frame of pure
// distractors is not relocalised, nor kept as a near miss (a pose on too few inliers, for the caller to check). With
// most matches wrong (loose matching after a long cover), AP3P RANSAC and the refinement on its consensus still find
// the pose.
#include "features/OrbVocabulary.h"
#include "features/VocabularyTrainer.h"
#include "loop/KeyframeDatabase.h"
#include "tracking/Relocalizer.h"
#include "tracking/WindowRelocalization.h"

#include "HSlamTestDescriptors.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace
{
using hslam::OrbDescriptor;
using hslam::SE3d;

const hslam::PinholeIntrinsics kK{500., 500., 319.5, 239.5};

using hslam_test::flipBits;
using hslam_test::randomDescriptor;

SE3d lookingFrom(const Eigen::Vector3d &rotationVector, const Eigen::Vector3d &cameraCentre)
{
  Eigen::Matrix<double, 6, 1> xi;
  xi << Eigen::Vector3d::Zero(), rotationVector;
  const SE3d wRc = SE3d::exp(xi);
  return SE3d(wRc.unitQuaternion(), cameraCentre).inverse(); // cTw
}

class Relocalization : public ::testing::Test
{
protected:
  void SetUp() override
  {
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> spread(-2., 2.), depth(4., 7.);
    // Place j: 300 points around (10 j, 0, 5.5), seen by keyframe j from (10 j, 0, 0) looking along +z.
    std::vector<std::vector<OrbDescriptor>> training;
    for (int j = 0; j < 3; ++j) {
      hslam::RelocalizationKeyframe kf;
      kf.id = 100 + j;
      for (int i = 0; i < 300; ++i) {
        kf.wX.emplace_back(10. * j + spread(rng), spread(rng), depth(rng));
        kf.descriptors.push_back(randomDescriptor(rng));
      }
      training.push_back(kf.descriptors);
      m_keyframes.push_back(kf);
      m_kfPoses.push_back(lookingFrom(Eigen::Vector3d::Zero(), Eigen::Vector3d(10. * j, 0., 0.)));
    }
    hslam::VocabularyTrainingOptions options;
    options.branching = 8;
    options.levels = 3;
    m_vocabulary = hslam::trainVocabulary(training, options);
    m_database.reset(new hslam::KeyframeDatabase(m_vocabulary.wordCount()));
    for (hslam::RelocalizationKeyframe &kf : m_keyframes) {
      hslam::BowVector bow;
      m_vocabulary.transform(kf.descriptors, bow, kf.direct, 1);
      m_database->add(kf.id, bow);
    }
  }

  //! The lost frame: place 1 seen from a displaced pose, descriptors with a few bits flipped, plus distractors.
  hslam::RelocalizationFrame lostFrame(const SE3d &cTw, int distractors, bool withPlace, std::mt19937_64 &rng)
  {
    hslam::RelocalizationFrame frame;
    std::normal_distribution<double> noise(0., 0.5);
    std::uniform_real_distribution<double> u(0., 640.), v(0., 480.);
    if (withPlace) {
      const hslam::RelocalizationKeyframe &kf = m_keyframes[1];
      for (std::size_t i = 0; i < kf.wX.size(); ++i) {
        const Eigen::Vector3d cX = cTw * kf.wX[i];
        const Eigen::Vector2d uv(kK.fx * cX.x() / cX.z() + kK.cx + noise(rng),
                                 kK.fy * cX.y() / cX.z() + kK.cy + noise(rng));
        if (uv.x() < 0 || uv.y() < 0 || uv.x() >= 640 || uv.y() >= 480) {
          continue;
        }
        frame.uv.push_back(uv);
        frame.descriptors.push_back(flipBits(kf.descriptors[i], 8, rng));
      }
    }
    for (int i = 0; i < distractors; ++i) {
      frame.uv.emplace_back(u(rng), v(rng));
      frame.descriptors.push_back(randomDescriptor(rng));
    }
    hslam::BowVector bow;
    m_vocabulary.transform(frame.descriptors, bow, frame.direct, 1);
    m_frameBow = bow;
    return frame;
  }

  std::vector<const hslam::RelocalizationKeyframe *> candidatesFor(const hslam::BowVector &bow)
  {
    std::vector<const hslam::RelocalizationKeyframe *> out;
    for (const auto &c : m_database->query(bow, hslam::KeyframeDatabase::Query())) {
      out.push_back(&m_keyframes[static_cast<std::size_t>(c.id - 100)]);
    }
    return out;
  }

  hslam::OrbVocabulary m_vocabulary;
  std::unique_ptr<hslam::KeyframeDatabase> m_database;
  std::vector<hslam::RelocalizationKeyframe> m_keyframes;
  std::vector<SE3d> m_kfPoses;
  hslam::BowVector m_frameBow;
};

TEST_F(Relocalization, RecoversThePoseOfALostFrameNearAKnownPlace)
{
  std::mt19937_64 rng(9);
  // 30 cm to the side and 6 degrees of yaw away from keyframe 101.
  const SE3d truth = lookingFrom(Eigen::Vector3d(0., 0.1, 0.), Eigen::Vector3d(10.3, 0.1, -0.2));
  const hslam::RelocalizationFrame frame = lostFrame(truth, 200, true, rng);
  const auto candidates = candidatesFor(m_frameBow);
  ASSERT_FALSE(candidates.empty());
  EXPECT_EQ(candidates.front()->id, 101);

  const hslam::RelocalizationResult result = hslam::relocalize(frame, candidates, kK);
  ASSERT_TRUE(result.success);
  EXPECT_EQ(result.keyframeId, 101);
  EXPECT_GT(result.inliers, 150);
  EXPECT_LT((result.cTw.inverse().translation() - truth.inverse().translation()).norm(), 0.01);
  EXPECT_LT((result.cTw.inverse() * truth).log().tail<3>().norm() * 180. / M_PI, 0.2);
  EXPECT_EQ(result.nearMissKeyframeId, -1); // a success leaves no near miss

  // Asked for more inliers than the place can give: no success, but the pose it found stays as the near miss, for a
  // caller to check against more of the map.
  hslam::RelocalizerOptions strict;
  strict.minInliers = 1000;
  const hslam::RelocalizationResult missed = hslam::relocalize(frame, candidates, kK, strict);
  EXPECT_FALSE(missed.success);
  ASSERT_EQ(missed.nearMissKeyframeId, 101);
  EXPECT_EQ(missed.nearMissInliers, result.inliers);
  EXPECT_LT((missed.nearMissCTw.inverse().translation() - truth.inverse().translation()).norm(), 0.01);
}

TEST_F(Relocalization, AFrameOfDistractorsIsNotRelocalised)
{
  std::mt19937_64 rng(10);
  const hslam::RelocalizationFrame frame = lostFrame(SE3d(), 500, false, rng);
  std::vector<const hslam::RelocalizationKeyframe *> all;
  for (const auto &kf : m_keyframes) {
    all.push_back(&kf);
  }
  const hslam::RelocalizationResult result = hslam::relocalize(frame, all, kK);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.candidatesTried, 3);
  EXPECT_EQ(result.nearMissKeyframeId, -1) << result.nearMissInliers << " inliers among distractors";
}
TEST_F(Relocalization, FindsThePoseWhenMostMatchesAreWrong)
{
  // 40 right matches among 300: the other keypoints carry the descriptors of other points of the keyframe at random
  // pixels (a repeated texture, or the loose matching WindowRelocalization uses), so every point matches somewhere.
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0., 0.5);
  std::uniform_real_distribution<double> u(0., 640.), v(0., 480.);
  const SE3d truth = lookingFrom(Eigen::Vector3d(0., 0.15, 0.), Eigen::Vector3d(10.3, 0.1, -0.2));
  const hslam::RelocalizationKeyframe &kf = m_keyframes[1];
  hslam::RelocalizationFrame frame;
  std::vector<bool> right;
  for (std::size_t i = 0; i < kf.wX.size(); ++i) {
    const Eigen::Vector3d cX = truth * kf.wX[i];
    Eigen::Vector2d uv(kK.fx * cX.x() / cX.z() + kK.cx + noise(rng), kK.fy * cX.y() / cX.z() + kK.cy + noise(rng));
    const bool inView = uv.x() >= 0 && uv.y() >= 0 && uv.x() < 640 && uv.y() < 480;
    const bool isRight = inView && std::count(right.begin(), right.end(), true) < 40;
    if (!isRight) {
      uv = Eigen::Vector2d(u(rng), v(rng));
    }
    frame.uv.push_back(uv);
    frame.descriptors.push_back(flipBits(kf.descriptors[i], 8, rng));
    right.push_back(isRight);
  }
  ASSERT_EQ(std::count(right.begin(), right.end(), true), 40);

  hslam::RelocalizerOptions options = hslam::WindowRelocalization::matchingOptions();
  options.minInliers = 30;
  const hslam::RelocalizationResult result = hslam::relocalize(frame, {&kf}, kK, options);
  ASSERT_TRUE(result.success) << result.matches << " matches, " << result.inliers << " inliers";
  EXPECT_GE(result.matches, 250);
  EXPECT_GE(result.inliers, 35);
  EXPECT_LE(result.inliers, 45); // the right ones, and no more than a few wrong ones that happen to agree
  EXPECT_LT((result.cTw.inverse().translation() - truth.inverse().translation()).norm(), 0.02);
  EXPECT_LT((result.cTw.inverse() * truth).log().tail<3>().norm() * 180. / M_PI, 0.3);
  ASSERT_EQ(static_cast<int>(result.inlierObservations.size()), result.inliers);
  EXPECT_GE(hslam::countReprojectionInliers(truth, result.inlierObservations, kK, 5.991), result.inliers - 3);
}
} // namespace

// Two consecutive fixes agree when a camera could have moved between them in a frame's time: rotation up to 10
// degrees, camera centre up to 10 % of the scene's median depth.
TEST(RelocalizationFixes, AgreeOnlyWithinAFramesMotion)
{
  const SE3d previous(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()).toRotationMatrix(), Eigen::Vector3d(1, 2, 3));
  const SE3d wMp = previous.inverse();
  auto moved = [&](double degrees, const Eigen::Vector3d &centreShift) {
    // Turn about the camera's own axis and shift its centre (world frame): the returned pose is cMw.
    const Eigen::Matrix3d wRc =
        wMp.rotationMatrix() * Eigen::AngleAxisd(degrees * M_PI / 180., Eigen::Vector3d::UnitX()).toRotationMatrix();
    return SE3d(wRc, wMp.translation() + centreShift).inverse();
  };
  const double depth = 2.;
  const hslam::FixAgreement same = hslam::compareFixes(previous, previous, depth);
  EXPECT_TRUE(same.agrees);
  EXPECT_NEAR(same.angleDeg, 0., 1e-6);
  EXPECT_NEAR(same.depthShare, 0., 1e-9);
  const hslam::FixAgreement small = hslam::compareFixes(previous, moved(2., Eigen::Vector3d(0.02, 0., 0.)), depth);
  EXPECT_TRUE(small.agrees);
  EXPECT_NEAR(small.angleDeg, 2., 1e-6);
  EXPECT_NEAR(small.depthShare, 0.01, 1e-9);
  EXPECT_FALSE(hslam::compareFixes(previous, moved(12., Eigen::Vector3d::Zero()), depth).agrees);
  EXPECT_FALSE(hslam::compareFixes(previous, moved(0., Eigen::Vector3d(0., 0.25, 0.)), depth).agrees);
  EXPECT_TRUE(hslam::compareFixes(previous, moved(0., Eigen::Vector3d(0., 0.15, 0.)), depth).agrees);
  EXPECT_FALSE(hslam::compareFixes(previous, previous, 0.).agrees); // no depth: nothing to compare against

  // The median depth is taken over the inliers in the frame the fix placed.
  hslam::RelocalizationResult r;
  r.cTw = previous;
  for (double z : {1., 4., 2., 3., 100.}) {
    hslam::ReprojectionObservation o;
    o.wX = wMp * Eigen::Vector3d(0.1, -0.2, z);
    r.inlierObservations.push_back(o);
  }
  EXPECT_NEAR(hslam::medianInlierDepth(r), 3., 1e-9);
  EXPECT_EQ(hslam::medianInlierDepth(hslam::RelocalizationResult()), 0.);
}
