// Loop detection pieces (issue 10): temporal consistency of candidate groups and the 3D-3D ORB matching rule.
#include "loop/LoopDetector.h"

#include <gtest/gtest.h>

#include <random>
#include <vector>

namespace
{
using hslam::LoopConsistency;
using hslam::LoopPoint;

TEST(LoopConsistency, AcceptsACandidateOnlyAfterConsecutiveAgreeingQueries)
{
  LoopConsistency consistency(3);
  // Keyframe 40's group {40, 41}, then 41's {41, 42}, then 42's {42, 43}: consistent three times in a row.
  EXPECT_TRUE(consistency.update({{40, {41}}}).empty());
  EXPECT_TRUE(consistency.update({{41, {42}}}).empty());
  EXPECT_EQ(consistency.update({{42, {43}}}), std::vector<int>({42}));
  // A query with no candidate forgets everything.
  consistency.update({});
  EXPECT_TRUE(consistency.update({{43, {44}}}).empty());
  // A candidate elsewhere breaks the chain: its group starts from zero.
  consistency.clear();
  EXPECT_TRUE(consistency.update({{10, {11}}}).empty());
  EXPECT_TRUE(consistency.update({{90, {91}}}).empty());
  EXPECT_TRUE(consistency.update({{11, {12}}}).empty()); // 10's group is no longer remembered
  // Two candidates in one query: each group is followed on its own.
  consistency.clear();
  EXPECT_TRUE(consistency.update({{10, {11}}, {50, {51}}}).empty());
  EXPECT_TRUE(consistency.update({{11, {}}, {51, {}}}).empty());
  EXPECT_EQ(consistency.update({{11, {12}}, {70, {}}}), std::vector<int>({11}));
}

TEST(LoopDetector, MatchesEachPointOnceWithRatioAndDistance)
{
  std::mt19937 rng(2);
  std::uniform_int_distribution<int> bit(0, 1);
  auto randomDescriptor = [&]() {
    hslam::OrbDescriptor d;
    for (int b = 0; b < 256; ++b) {
      if (bit(rng)) {
        d.words[static_cast<size_t>(b / 64)] |= (uint64_t(1) << (b % 64));
      }
    }
    return d;
  };
  std::vector<LoopPoint> a(30), b;
  for (LoopPoint &p : a) {
    p.orb = randomDescriptor();
  }
  // b: copies of a[0..19] with 10 bits flipped (true matches), then 10 random descriptors (no match).
  for (int i = 0; i < 20; ++i) {
    LoopPoint p = a[static_cast<size_t>(i)];
    for (int k = 0; k < 10; ++k) {
      p.orb.words[static_cast<size_t>(k % 4)] ^= (uint64_t(1) << (7 * k));
    }
    b.push_back(p);
  }
  for (int i = 0; i < 10; ++i) {
    LoopPoint p;
    p.orb = randomDescriptor();
    b.push_back(p);
  }
  // A duplicate of a[3] in b: a[3] must go to the closer of the two only.
  LoopPoint dup = a[3];
  b.push_back(dup);
  const std::vector<std::pair<int, int>> m = hslam::matchLoopPoints(a, b, 50, 0.75);
  ASSERT_EQ(m.size(), 20u);
  for (const auto &pr : m) {
    EXPECT_LT(pr.first, 20);
    if (pr.first == 3) {
      EXPECT_EQ(pr.second, 30); // the exact copy
    } else {
      EXPECT_EQ(pr.second, pr.first);
    }
  }
  // Nothing within the distance: nothing matched.
  EXPECT_TRUE(hslam::matchLoopPoints(a, std::vector<LoopPoint>(b.begin() + 20, b.begin() + 30), 50, 0.75).empty());
}
} // namespace
