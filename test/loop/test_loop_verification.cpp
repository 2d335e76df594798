// Loop verification (issue 50): a hand-built pair of keyframe sides with a known similarity and wrong matches, and
// the loop closer's hand-over (a keyframe leaving the window becomes a database entry with depth-carrying features).
#include "loop/LoopVerification.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace
{
using hslam::LoopKeyframe;
using hslam::LoopSideKeyframe;
using hslam::OrbDescriptor;
using hslam::PinholeIntrinsics;
using hslam::SE3d;
using hslam::Sim3d;

OrbDescriptor randomDescriptor(std::mt19937 &rng)
{
  OrbDescriptor d;
  for (auto &w : d.words) {
    w = (static_cast<std::uint64_t>(rng()) << 32) | rng();
  }
  return d;
}

//! \e d with \e bits bits flipped (a re-detection of the same corner).
OrbDescriptor noisy(OrbDescriptor d, int bits, std::mt19937 &rng)
{
  for (int k = 0; k < bits; ++k) {
    const int b = static_cast<int>(rng() % 256);
    d.words[static_cast<size_t>(b / 64)] ^= std::uint64_t(1) << (b % 64);
  }
  return d;
}

const PinholeIntrinsics K{500., 500., 320., 240.};

//! Scene points seen by the candidate (camera 1) and by the query (camera 2 = S21 camera 1, in its own scale).
struct Pair {
  LoopKeyframe query, candidate;
  Sim3d S21;
};

Pair makePair(int shared, int outliers, int onlyInOne, unsigned int seed)
{
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> xy(-1.5, 1.5), z(2., 5.);
  Pair p;
  // The query sees the place from 0.2 units aside, turned by 5 degrees, in a map whose scale drifted to 0.8.
  const Eigen::Quaterniond q(Eigen::AngleAxisd(5. * M_PI / 180., Eigen::Vector3d(0.2, 1., 0.1).normalized()));
  p.S21 = Sim3d(q, Eigen::Vector3d(0.2, -0.05, 0.1), 0.8);
  p.query.id = 200;
  p.candidate.id = 20;
  for (int i = 0; i < shared + outliers + onlyInOne; ++i) {
    const Eigen::Vector3d X1(xy(rng), xy(rng), z(rng));
    const OrbDescriptor d = randomDescriptor(rng);
    p.candidate.X.push_back(X1.cast<float>());
    p.candidate.orb.push_back(d);
    p.candidate.octave.push_back(0);
    if (i >= shared + outliers) {
      continue; // seen by the candidate only
    }
    // Outliers: the descriptor matches but the point is elsewhere (a repeated texture).
    const Eigen::Vector3d X2 = i < shared ? Eigen::Vector3d(p.S21 * X1) : Eigen::Vector3d(xy(rng), xy(rng), z(rng));
    p.query.X.push_back(X2.cast<float>());
    p.query.orb.push_back(noisy(d, 12, rng));
    p.query.octave.push_back(0);
  }
  for (int i = 0; i < onlyInOne; ++i) { // seen by the query only
    p.query.X.push_back(Eigen::Vector3f(static_cast<float>(xy(rng)), static_cast<float>(xy(rng)), 3.f));
    p.query.orb.push_back(randomDescriptor(rng));
    p.query.octave.push_back(0);
  }
  return p;
}

TEST(LoopVerification, RecoversAKnownSimilarityDespiteWrongMatches)
{
  const Pair p = makePair(60, 30, 40, 3);
  const hslam::LoopVerification v =
      hslam::verifyLoopSides({{&p.query, SE3d()}}, {{&p.candidate, SE3d()}}, K, hslam::LoopVerificationOptions());
  ASSERT_TRUE(v.estimate.success);
  EXPECT_GE(v.matches, 85); // the 60 right and most of the 30 wrong ones pass the descriptor test
  EXPECT_GE(v.estimate.inlierCount, 55);
  EXPECT_LE(v.estimate.inlierCount, 62); // the wrong ones are not explained
  EXPECT_NEAR(v.estimate.S21.scale(), 0.8, 1e-3);
  EXPECT_LT((v.estimate.S21.translation() - p.S21.translation()).norm(), 1e-3);
  EXPECT_LT(v.estimate.S21.unitQuaternion().angularDistance(p.S21.unitQuaternion()), 1e-4);
  EXPECT_EQ(static_cast<int>(v.inliers.size()), v.estimate.inlierCount);
}

TEST(LoopVerification, RejectsAPlaceThatOnlyLooksAlike)
{
  // Every descriptor matches, no geometry agrees: no similarity explains 20 of them.
  const Pair p = makePair(0, 80, 40, 4);
  const hslam::LoopVerification v =
      hslam::verifyLoopSides({{&p.query, SE3d()}}, {{&p.candidate, SE3d()}}, K, hslam::LoopVerificationOptions());
  EXPECT_GE(v.matches, 60);
  EXPECT_FALSE(v.estimate.success);
  EXPECT_TRUE(v.inliers.empty());
}

TEST(LoopVerification, WidensThroughACoVisibleKeyframe)
{
  // The candidate alone shares 25 points with the query (under minInliers, 40); its neighbour, 0.3 units to the side,
  // shares 25 more. Expressed in the candidate's camera through its pose, the neighbour's points complete the side.
  const Pair p = makePair(50, 0, 20, 5);
  LoopKeyframe candidate = p.candidate, neighbour = p.candidate;
  const SE3d candidateMneighbour(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.3, 0., 0.));
  candidate.X.resize(25);
  candidate.orb.resize(25);
  candidate.octave.resize(25);
  neighbour.id = 21;
  for (Eigen::Vector3f &X : neighbour.X) { // the neighbour holds its points in its own camera
    X = (candidateMneighbour.inverse() * Eigen::Vector3d(X.cast<double>())).cast<float>();
  }
  neighbour.X.erase(neighbour.X.begin(), neighbour.X.begin() + 25);
  neighbour.orb.erase(neighbour.orb.begin(), neighbour.orb.begin() + 25);
  neighbour.octave.erase(neighbour.octave.begin(), neighbour.octave.begin() + 25);
  const hslam::LoopVerificationOptions options;
  EXPECT_FALSE(hslam::verifyLoopSides({{&p.query, SE3d()}}, {{&candidate, SE3d()}}, K, options).estimate.success);
  const hslam::LoopVerification v = hslam::verifyLoopSides(
      {{&p.query, SE3d()}}, {{&candidate, SE3d()}, {&neighbour, candidateMneighbour}}, K, options);
  ASSERT_TRUE(v.estimate.success);
  EXPECT_GE(v.estimate.inlierCount, 45);
  EXPECT_EQ(v.centralInliers, 25);
  EXPECT_NEAR(v.estimate.S21.scale(), 0.8, 1e-3);
}

TEST(LoopVerification, NeedsTheTwoEndsThemselves)
{
  // 60 points shared, but the candidate itself holds only 10 of them: its neighbour alone sees the place. A
  // similarity between the two ends is not measured by it (the neighbours' poses stand in for the loop).
  const Pair p = makePair(60, 0, 20, 6);
  LoopKeyframe candidate = p.candidate, neighbour = p.candidate;
  candidate.X.resize(10);
  candidate.orb.resize(10);
  candidate.octave.resize(10);
  neighbour.id = 21;
  const hslam::LoopVerification v = hslam::verifyLoopSides(
      {{&p.query, SE3d()}}, {{&candidate, SE3d()}, {&neighbour, SE3d()}}, K, hslam::LoopVerificationOptions());
  EXPECT_GE(v.matches, 50);
  EXPECT_LE(v.centralInliers, 10);
  EXPECT_FALSE(v.estimate.success);
}

TEST(LoopVerification, GuidedMatchingFindsByProjectionWhatTheDescriptorsLeftAmbiguous)
{
  // 60 shared points; 36 of them have a look-alike elsewhere in the query (2 bits from the right corner), so the
  // ratio test leaves 24 descriptor matches, under minInliers (40). Guided matching finds the 36 where the
  // similarity projects them. A query point just in front of the camera projects 10^11 pixels away: ignored.
  Pair p = makePair(60, 0, 20, 7);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> xy(-1.5, 1.5);
  for (size_t i = 24; i < 60; ++i) {
    p.query.X.push_back(Eigen::Vector3f(static_cast<float>(xy(rng)), static_cast<float>(xy(rng)), 4.f));
    p.query.orb.push_back(noisy(p.query.orb[i], 2, rng));
    p.query.octave.push_back(0);
  }
  p.query.X.push_back(Eigen::Vector3f(1.f, 1.f, 1e-8f));
  p.query.orb.push_back(randomDescriptor(rng));
  p.query.octave.push_back(0);
  const hslam::LoopVerification v =
      hslam::verifyLoopSides({{&p.query, SE3d()}}, {{&p.candidate, SE3d()}}, K, hslam::LoopVerificationOptions());
  EXPECT_LE(v.matches, 30);
  EXPECT_GE(v.guidedMatches, 30);
  ASSERT_TRUE(v.estimate.success);
  EXPECT_GE(v.estimate.inlierCount, 55);
  EXPECT_NEAR(v.estimate.S21.scale(), 0.8, 1e-3);
}
} // namespace
