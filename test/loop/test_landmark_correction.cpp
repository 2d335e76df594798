// A landmark seen in metres (an AprilTag, issue 53) as a constraint of loop closure's pose graph: seen again after a
// lap whose scale drifted, it bends the map back to the metres of the first visit, as a loop would bring back the
// place (loop/LoopCorrection.h, solveLandmarkCorrection(); PoseGraph.h, metric sightings).
#include "features/OrbVocabulary.h"
#include "loop/LoopCloser.h"
#include "loop/LoopCorrection.h"
#include "loop/PoseGraph.h"
#include "map/GlobalMap.h"

#include "CircleRun.h"

#include <gtest/gtest.h>

#include <visp3/hslam/vpHSlamParameters.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <vector>

namespace
{
using hslam::SE3d;
using hslam::Sim3d;

//! Two laps of 20 keyframes round a circle, the last kWindow in the window, whose odometry grows its scale by
//! kScaleDrift per keyframe (a monocular map's scale drift), and a tag 2 m in front of the first places.
struct DriftedLaps {
  static constexpr int kStored = 40, kWindow = 3, kPlaces = 20;
  static constexpr double kScaleDrift = 0.005;
  hslam::GlobalMap map;
  std::map<int, SE3d> window;
  SE3d wMt; //!< the tag in the true world, metres

  static SE3d truth(int k) { return hslam_test::circleCamera(k, kPlaces, 0.); } // cMw, metres

  DriftedLaps()
  {
    wMt = truth(1).inverse() *
          SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX())), Eigen::Vector3d(0.1, 0., 2.));
    SE3d wMc = truth(0).inverse();
    for (int k = 0; k < kStored + kWindow; ++k) {
      if (k > 0) { // the true motion, its translation scaled by the drift so far
        SE3d step = truth(k - 1) * truth(k).inverse();
        step.translation() *= std::pow(1. + kScaleDrift, k);
        wMc = wMc * step;
        hslam::PosePoseEdge e;
        e.from = k - 1;
        e.to = k;
        e.toMfrom = wMc.inverse() * pose(k - 1).inverse();
        map.addPosePoseEdge(e);
      }
      if (k < kStored) {
        hslam::GlobalKeyframe g;
        g.id = k;
        g.cMw = wMc.inverse();
        map.add(g);
      } else {
        window[k] = wMc.inverse();
      }
    }
  }
  SE3d pose(int k) const { return window.count(k) ? window.at(k) : map.find(k)->cMw; }
  //! Metres per map unit at the window (the metric frame's scale there).
  static double metresPerUnit() { return std::pow(1. + kScaleDrift, -(kStored + 1)); }
  //! The true sighting of the tag from keyframe \e k.
  hslam::LandmarkSighting sighting(int k) const
  {
    const SE3d cMt = truth(k) * wMt;
    return {k, 0, cMt, cMt.translation().norm()};
  }
  //! How far keyframes 0 and 1 are apart in metres by the map's unit at the window, against the truth (1: right).
  double firstStepScale() const
  {
    const double map01 = (pose(0).inverse().translation() - pose(1).inverse().translation()).norm();
    const double true01 = (truth(0).inverse().translation() - truth(1).inverse().translation()).norm();
    return map01 * metresPerUnit() / true01;
  }
  //! Metres between keyframe 0 and keyframe 40, the same place (0 in the truth).
  double closingMetres() const
  {
    return (pose(0).inverse().translation() - pose(kStored).inverse().translation()).norm() * metresPerUnit();
  }
  bool correct(const hslam::LandmarkSightings &landmarks)
  {
    std::vector<std::pair<int, Sim3d>> solution;
    if (!hslam::solveLandmarkCorrection(map, 0, window, {}, landmarks, solution)) {
      return false;
    }
    for (const auto &s : solution) {
      map.applySimilarity(s.first, s.second);
    }
    return true;
  }
};

hslam::LandmarkSightings seenAtBothVisits(const DriftedLaps &laps)
{
  hslam::LandmarkSightings landmarks;
  landmarks.metresPerUnit = DriftedLaps::metresPerUnit();
  for (int k : {0, 1, 2, 40, 41, 42}) {
    landmarks.sightings.push_back(laps.sighting(k));
  }
  return landmarks;
}
} // namespace

TEST(LandmarkCorrection, ATagSeenAgainUndoesTheScaleDriftOfTheLapBetween)
{
  DriftedLaps laps;
  const double scaleBefore = laps.firstStepScale(), closingBefore = laps.closingMetres();
  ASSERT_TRUE(laps.correct(seenAtBothVisits(laps)));
  std::printf("first step's scale %.4f -> %.4f, places 0 and 40 apart by %.3f -> %.3f m\n", scaleBefore,
              laps.firstStepScale(), closingBefore, laps.closingMetres());
  EXPECT_LT(scaleBefore, 0.85); // the first lap was mapped about 20 % too small for the window's metres
  EXPECT_NEAR(laps.firstStepScale(), 1., 0.03);
  EXPECT_LT(laps.closingMetres(), 0.1 * closingBefore);
}

TEST(LandmarkCorrection, AFlippedDetectionDoesNotBendTheMap)
{
  // A small tag seen face-on can be detected with its pose flipped by tens of degrees: the robust cost lets it go.
  DriftedLaps laps;
  hslam::LandmarkSightings landmarks = seenAtBothVisits(laps);
  hslam::LandmarkSighting flipped = laps.sighting(2);
  flipped.cMl =
      flipped.cMl * SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY())), Eigen::Vector3d::Zero());
  landmarks.sightings[2] = flipped;
  const double closingBefore = laps.closingMetres();
  ASSERT_TRUE(laps.correct(landmarks));
  // Keyframe 2's orientation against its neighbour's, which the odometry had right: followed by the flipped sighting,
  // it would turn by a good part of 40 degrees.
  const double turnDeg = (laps.pose(2).unitQuaternion() * laps.pose(1).unitQuaternion().conjugate())
                             .angularDistance(DriftedLaps::truth(2).unitQuaternion() *
                                              DriftedLaps::truth(1).unitQuaternion().conjugate()) *
                         180. / M_PI;
  std::printf("keyframe 2 turned %.3f degree from its neighbour's true relative orientation\n", turnDeg);
  EXPECT_LT(turnDeg, 0.5);
  EXPECT_NEAR(laps.firstStepScale(), 1., 0.03);
  EXPECT_LT(laps.closingMetres(), 0.1 * closingBefore);
}

TEST(LandmarkCorrection, NothingToCorrectWithoutASightingFromTheWindowOrWhenNotMetric)
{
  DriftedLaps laps;
  hslam::LandmarkSightings landmarks = seenAtBothVisits(laps);
  landmarks.sightings.resize(3); // the first visit only
  EXPECT_FALSE(laps.correct(landmarks));
  landmarks = seenAtBothVisits(laps);
  landmarks.metresPerUnit = 0.; // the metric frame is not trusted yet
  EXPECT_FALSE(laps.correct(landmarks));
}

TEST(LandmarkCorrection, RealTimeTheLoopClosersThreadSolvesItWithTheSightingsGivenBefore)
{
  // Real time: the sightings and the correction are queued in order to the loop closer's thread, which solves on a
  // copy of the map; the mapper takes the solution and applies it. The solution is the one solved in the caller.
  DriftedLaps laps;
  std::vector<std::pair<int, Sim3d>> expected;
  ASSERT_TRUE(hslam::solveLandmarkCorrection(laps.map, 0, laps.window, {}, seenAtBothVisits(laps), expected));
  const hslam::OrbVocabulary vocabulary;
  hslam::LoopCloser closer(vpHSlamParameters().loop, hslam::PinholeIntrinsics{300., 300., 160., 120.}, vocabulary);
  closer.startThread();
  hslam::LoopCloser::Correction correction;
  closer.queueLandmarkCorrection(42, laps.map.graphCopy(), laps.window); // no sightings given yet: nothing solved
  EXPECT_FALSE(closer.takeCorrection(correction, true));
  closer.setLandmarkSightings(seenAtBothVisits(laps));
  closer.queueLandmarkCorrection(42, laps.map.graphCopy(), laps.window);
  ASSERT_TRUE(closer.takeCorrection(correction, true));
  EXPECT_TRUE(correction.landmark);
  EXPECT_EQ(correction.loop.keyframe, 42);
  ASSERT_EQ(correction.solution.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(correction.solution[i].first, expected[i].first);
    EXPECT_LT((correction.solution[i].second.matrix() - expected[i].second.matrix()).norm(), 1e-9);
  }
  // The mapper applied it: counted as a landmark's correction, not a loop's.
  closer.recordCorrectionApplied(correction.solveMs, true);
  EXPECT_EQ(closer.statistics().applied.landmarkCorrected, 1);
  EXPECT_EQ(closer.statistics().applied.corrected, 0);
}

TEST(LandmarkCorrection, TheSparseSolverReachesCeresSolutionWithSightings)
{
  // Large graphs are solved by the sparse solver (PoseGraph.h): with sightings it must reach the optimum Ceres
  // reaches, a flipped sighting included (its robust cost).
  DriftedLaps laps;
  hslam::LandmarkSightings landmarks = seenAtBothVisits(laps);
  landmarks.sightings[1].cMl =
      landmarks.sightings[1].cMl *
      SE3d(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY())), Eigen::Vector3d(0.05, 0., 0.));
  const auto build = [&]() {
    hslam::PoseGraph graph;
    for (int k = 0; k < DriftedLaps::kStored + DriftedLaps::kWindow; ++k) {
      graph.addVertex(k, Sim3d(laps.pose(k), 1.), laps.window.count(k) > 0);
      if (k > 0) {
        graph.addEdgeFromCurrent(k - 1, k);
      }
    }
    const double m = DriftedLaps::metresPerUnit();
    const hslam::LandmarkSighting &newest = landmarks.sightings.back();
    const Sim3d Skl(newest.cMl.unitQuaternion(), newest.cMl.translation() / m, 1. / m);
    graph.addVertex(-2, Skl.inverse() * Sim3d(laps.pose(newest.keyframe), 1.), false);
    for (const hslam::LandmarkSighting &s : landmarks.sightings) {
      hslam::PoseGraphSighting e;
      e.landmark = -2;
      e.keyframe = s.keyframe;
      e.cMl = s.cMl;
      e.sqrtInformation.topLeftCorner<3, 3>() /= 0.026;
      e.sqrtInformation.bottomRightCorner<3, 3>() /= 0.003 * s.range;
      e.robustScale = 3.;
      e.weight = 1e-2;
      graph.addSighting(e);
    }
    return graph;
  };
  hslam::PoseGraph ceres = build(), sparse = build();
  const hslam::PoseGraphSummary c = ceres.optimize(50, hslam::PoseGraph::Solver::ceres);
  const hslam::PoseGraphSummary s = sparse.optimize(50, hslam::PoseGraph::Solver::sparse);
  ASSERT_TRUE(c.usable && s.usable);
  std::printf("cost %.6g -> %.6g (Ceres, %d iterations), %.6g -> %.6g (sparse, %d iterations)\n", c.initialCost,
              c.finalCost, c.iterations, s.initialCost, s.finalCost, s.iterations);
  EXPECT_NEAR(s.initialCost, c.initialCost, 1e-9 * c.initialCost);
  EXPECT_LT(c.finalCost, 0.5 * c.initialCost); // the drift is real: the chain keeps part of its cost
  EXPECT_NEAR(s.finalCost, c.finalCost, 1e-3 * c.finalCost);
  for (int k = -2; k < DriftedLaps::kStored; ++k) {
    if (k == -1) {
      continue;
    }
    const Sim3d d = sparse.vertex(k) * ceres.vertex(k).inverse();
    EXPECT_LT(d.log().norm(), 1e-4) << "vertex " << k;
  }
}
