// Loop verification and correction building blocks (issue 10): Horn's closed-form Sim(3), RANSAC with two-way
// reprojection and refinement, the Sim(3) pose graph on a drifted loop, and the loop correction's graph (the loops
// it keeps).
#include "loop/LoopCorrection.h"
#include "loop/PoseGraph.h"
#include "loop/Sim3Solver.h"
#include "map/GlobalMap.h"

#include "CircleRun.h"
#include "HSlamTestCameras.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <vector>

namespace
{
using hslam::PinholeIntrinsics;
using hslam::Sim3d;

Sim3d randomSim3(std::mt19937 &rng, double trans, double rot, double logScale)
{
  std::uniform_real_distribution<double> u(-1., 1.);
  Sim3d::Tangent xi;
  xi << trans * u(rng), trans * u(rng), trans * u(rng), rot * u(rng), rot * u(rng), rot * u(rng), logScale * u(rng);
  return Sim3d::exp(xi);
}

double transformError(const Sim3d &a, const Sim3d &b)
{
  return (a * b.inverse()).log().norm();
}

Eigen::Vector2d projectPoint(const PinholeIntrinsics &K, const Eigen::Vector3d &X)
{
  return Eigen::Vector2d(K.fx * X.x() / X.z() + K.cx, K.fy * X.y() / X.z() + K.cy);
}

TEST(Sim3Solver, HornRecoversAKnownSimilarityExactly)
{
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-2., 2.);
  for (int trial = 0; trial < 20; ++trial) {
    const Sim3d S = randomSim3(rng, 1., 1.5, 0.7);
    std::vector<Eigen::Vector3d> X1, X2;
    for (int i = 0; i < 3 + trial; ++i) {
      X1.emplace_back(u(rng), u(rng), 3. + u(rng));
      X2.push_back(S * X1.back());
    }
    const Sim3d est = hslam::hornSim3(X1, X2);
    EXPECT_LT(transformError(est, S), 1e-9) << "trial " << trial;
    EXPECT_NEAR(est.scale(), S.scale(), 1e-9 * S.scale());
  }
  // Too few points or all coincident: refused.
  EXPECT_THROW(hslam::hornSim3({Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()},
                               {Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()}),
               vpHSlamException);
  EXPECT_THROW(hslam::hornSim3(std::vector<Eigen::Vector3d>(3, Eigen::Vector3d::Ones()),
                               std::vector<Eigen::Vector3d>(3, Eigen::Vector3d::Zero())),
               vpHSlamException);
}

TEST(Sim3Solver, RefinementRefusesAScaleNoMapCanHave)
{
  // A RANSAC hypothesis from a degenerate sample can carry a scale beyond e^+-20; Ceres aborts the process on a
  // parameter block its manifold cannot be evaluated at (hslam_many_laps did, at 650 stored keyframes). The
  // refinement must refuse such a start, and must still run from a scale on the bound itself.
  const PinholeIntrinsics K = hslam_test::vgaPinhole500();
  std::vector<hslam::Sim3Correspondence> matches;
  for (int i = 0; i < 12; ++i) {
    hslam::Sim3Correspondence m;
    m.X1 = Eigen::Vector3d(0.2 * (i % 4) - 0.3, 0.15 * (i / 4) - 0.15, 3. + 0.1 * i);
    m.X2 = m.X1;
    m.uv1 = m.uv2 = projectPoint(K, m.X1);
    matches.push_back(m);
  }
  for (double logScale : {-21.3, 25.}) {
    Sim3d S(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), std::exp(logScale));
    const Sim3d before = S;
    EXPECT_FALSE(hslam::refineSim3(matches, K, K, 1., S)) << "log-scale " << logScale;
    EXPECT_EQ(S.matrix(), before.matrix());
  }
  Sim3d onTheBound(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.01, 0., 0.), std::exp(-20.));
  hslam::refineSim3(matches, K, K, 1., onTheBound); // whatever it returns, it returns
  EXPECT_TRUE(onTheBound.translation().allFinite());
}

TEST(Sim3Solver, RansacFindsTheSimilarityDespiteNoiseAndOutliers)
{
  // Two keyframes seeing the same 150 points; the second keyframe's map has a scale of 1.6 (monocular drift).
  // Pixels have 0.5 px of noise, the 3D points 1 % depth noise, and 40 % of the matches are wrong.
  const PinholeIntrinsics K = hslam_test::vgaPinhole500();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> px(20., 620.), py(20., 460.), depth(2., 6.), unit(0., 1.);
  std::normal_distribution<double> pixelNoise(0., 0.5), depthNoise(0., 0.01);
  Sim3d::Tangent xi;
  xi << 0.3, -0.1, 0.2, 0.05, 0.2, -0.03, std::log(1.6);
  const Sim3d S21 = Sim3d::exp(xi);
  std::vector<hslam::Sim3Correspondence> matches;
  std::vector<bool> truthInlier;
  for (int i = 0; i < 150; ++i) {
    const double z = depth(rng);
    const Eigen::Vector2d uv(px(rng), py(rng));
    const Eigen::Vector3d X1((uv.x() - K.cx) / K.fx * z, (uv.y() - K.cy) / K.fy * z, z);
    const Eigen::Vector3d X2 = S21 * X1;
    if (X2.z() <= 0.5) {
      continue;
    }
    hslam::Sim3Correspondence m;
    m.uv1 = projectPoint(K, X1) + Eigen::Vector2d(pixelNoise(rng), pixelNoise(rng));
    m.uv2 = projectPoint(K, X2) + Eigen::Vector2d(pixelNoise(rng), pixelNoise(rng));
    m.X1 = X1 * (1. + depthNoise(rng));
    m.X2 = X2 * (1. + depthNoise(rng));
    const bool wrong = unit(rng) < 0.4;
    if (wrong) { // another point's second view
      const double z2 = depth(rng);
      const Eigen::Vector2d other(px(rng), py(rng));
      m.X2 = Eigen::Vector3d((other.x() - K.cx) / K.fx * z2, (other.y() - K.cy) / K.fy * z2, z2);
      m.uv2 = projectPoint(K, m.X2);
    }
    matches.push_back(m);
    truthInlier.push_back(!wrong);
  }
  const hslam::Sim3Estimate est = hslam::estimateSim3Ransac(matches, K, K);
  int agree = 0, trueInliers = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    agree += est.inliers[i] == truthInlier[i] ? 1 : 0;
    trueInliers += truthInlier[i] ? 1 : 0;
  }
  std::printf("Sim3 RANSAC: %d of %zu inliers (%d true), %d hypotheses, rms %.3f px, scale %.4f (truth 1.6), "
              "error %.2e\n",
              est.inlierCount, matches.size(), trueInliers, est.iterations, est.rmsReprojectionPx, est.S21.scale(),
              transformError(est.S21, S21));
  ASSERT_TRUE(est.success);
  EXPECT_NEAR(est.S21.scale(), 1.6, 0.01);
  EXPECT_LT(transformError(est.S21, S21), 0.01);
  EXPECT_GE(agree, static_cast<int>(matches.size()) - 3);
  EXPECT_LT(est.rmsReprojectionPx, 1.5);
  // Only wrong matches: no similarity explains 20 of them.
  std::vector<hslam::Sim3Correspondence> wrongOnly;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (!truthInlier[i]) {
      wrongOnly.push_back(matches[i]);
    }
  }
  EXPECT_FALSE(hslam::estimateSim3Ransac(wrongOnly, K, K).success);
}

//! 60 keyframes on a circle of radius 2 m (S_iw, world to camera), and the relative drift of one odometry step.
struct DriftedLoop {
  static constexpr int n = 60;
  std::vector<Sim3d> truth;
  Sim3d D;
  DriftedLoop()
  {
    for (int k = 0; k < n; ++k) {
      const double a = 2. * M_PI * k / n;
      const Eigen::Matrix3d wRc = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix();
      const Eigen::Vector3d wtc(2. * std::sin(a), 0.1 * std::sin(3. * a), 2. * std::cos(a));
      truth.push_back(Sim3d(wRc, wtc, 1.).inverse());
    }
    Sim3d::Tangent drift; // 1 cm, 0.3 degree of yaw and 0.5 % of scale per step
    drift << 0.01, 0., 0., 0., 0.3 * M_PI / 180., 0., 0.005;
    D = Sim3d::exp(drift);
  }
  //! Vertices chained from drifted steps (vertex 0 fixed at the truth); edges drifted too when \e driftedEdges.
  void build(hslam::PoseGraph &graph, bool driftedEdges) const
  {
    Sim3d chained = truth[0];
    graph.addVertex(0, chained, true);
    for (int k = 1; k < n; ++k) {
      const Sim3d exact = truth[static_cast<size_t>(k)] * truth[static_cast<size_t>(k - 1)].inverse();
      chained = D * exact * chained;
      graph.addVertex(k, chained);
      hslam::PoseGraphEdge e;
      e.i = k - 1;
      e.j = k;
      e.Sji = driftedEdges ? D * exact : exact;
      graph.addEdge(e);
    }
    hslam::PoseGraphEdge loop; // the loop edge is exact
    loop.i = n - 1;
    loop.j = 0;
    loop.Sji = truth[0] * truth[static_cast<size_t>(n - 1)].inverse();
    loop.sqrtInformation *= 10.;
    graph.addEdge(loop);
  }
  double largestCentreError(const hslam::PoseGraph &graph) const
  {
    double worst = 0.;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d c = graph.vertex(k).inverse().translation();
      worst = std::max(worst, (c - truth[static_cast<size_t>(k)].inverse().translation()).norm());
    }
    return worst;
  }
};

class PoseGraphSolvers : public ::testing::TestWithParam<hslam::PoseGraph::Solver>
{
};
INSTANTIATE_TEST_SUITE_P(PoseGraph, PoseGraphSolvers,
                         ::testing::Values(hslam::PoseGraph::Solver::ceres, hslam::PoseGraph::Solver::sparse),
                         [](const ::testing::TestParamInfo<hslam::PoseGraph::Solver> &info) {
                           return info.param == hslam::PoseGraph::Solver::ceres ? "Ceres" : "Sparse";
                         });

TEST_P(PoseGraphSolvers, RecoversGroundTruthFromADriftedStart)
{
  // Exact relative constraints, vertices initialised by chaining drifted steps (0.75 m off at the end of the loop,
  // 35 % of scale): the optimum is the ground truth, and the solver must reach it.
  const DriftedLoop loop;
  hslam::PoseGraph graph;
  loop.build(graph, false);
  const double before = loop.largestCentreError(graph);
  const hslam::PoseGraphSummary s = graph.optimize(50, GetParam());
  const double after = loop.largestCentreError(graph);
  std::printf("pose graph (exact edges): largest centre error %.3f m -> %.2e m, %d iterations, %.1f ms\n", before,
              after, s.iterations, s.ms);
  ASSERT_TRUE(s.usable);
  EXPECT_GT(before, 0.5);
  EXPECT_LT(after, 1e-6);
  for (int k = 0; k < DriftedLoop::n; ++k) {
    EXPECT_LT(transformError(graph.vertex(k), loop.truth[static_cast<size_t>(k)]), 1e-6) << "vertex " << k;
  }
  EXPECT_THROW(graph.vertex(DriftedLoop::n + 5), vpHSlamException);
  hslam::PoseGraphEdge bad;
  bad.i = 0;
  bad.j = DriftedLoop::n + 5;
  EXPECT_THROW(graph.addEdge(bad), vpHSlamException);
}

TEST_P(PoseGraphSolvers, SpreadsSystematicDriftOverTheLoop)
{
  // Every odometry edge carries the same drift and one exact loop edge contradicts them: the least-squares answer
  // spreads the contradiction along the loop, so the worst keyframe must end well inside the drifted one's error,
  // the fixed vertex must not move, and the cost must drop by orders of magnitude.
  const DriftedLoop loop;
  hslam::PoseGraph graph;
  loop.build(graph, true);
  const double before = loop.largestCentreError(graph);
  const hslam::PoseGraphSummary s = graph.optimize(50, GetParam());
  const double after = loop.largestCentreError(graph);
  std::printf("pose graph (drifted edges): largest centre error %.3f m -> %.3f m, cost %.3g -> %.3g\n", before, after,
              s.initialCost, s.finalCost);
  ASSERT_TRUE(s.usable);
  EXPECT_LT(after, 0.3 * before);
  EXPECT_LT(s.finalCost, 0.01 * s.initialCost);
  EXPECT_LT(transformError(graph.vertex(0), loop.truth[0]), 1e-12);
}

TEST(PoseGraph, AVertexWithAScaleNoMapCanHaveIsRefusedNotAborted)
{
  const DriftedLoop loop;
  hslam::PoseGraph graph;
  loop.build(graph, true);
  graph.addVertex(5, Sim3d(loop.truth[5].unitQuaternion(), loop.truth[5].translation(), std::exp(-21.)));
  const Sim3d before = graph.vertex(7);
  const hslam::PoseGraphSummary s = graph.optimize(50, hslam::PoseGraph::Solver::ceres);
  EXPECT_FALSE(s.usable);
  EXPECT_EQ(graph.vertex(7).matrix(), before.matrix()); // nothing written
}

TEST(PoseGraph, SparseSolverReachesCeresSolution)
{
  // The drifted loop, whose optimum has residuals left on every edge (where the sparse solver's first-order Jacobians
  // are not exact): both solvers must land on the same vertices and the same cost, and the automatic choice must
  // take Ceres for a graph this small.
  const DriftedLoop loop;
  hslam::PoseGraph ceres, sparse, automatic;
  loop.build(ceres, true);
  loop.build(sparse, true);
  loop.build(automatic, true);
  const hslam::PoseGraphSummary c = ceres.optimize(50, hslam::PoseGraph::Solver::ceres);
  const hslam::PoseGraphSummary s = sparse.optimize(50, hslam::PoseGraph::Solver::sparse);
  const hslam::PoseGraphSummary a = automatic.optimize(50);
  ASSERT_TRUE(c.usable && s.usable && a.usable);
  std::printf("drifted loop: cost %.6g (Ceres, %d iterations) and %.6g (sparse, %d iterations)\n", c.finalCost,
              c.iterations, s.finalCost, s.iterations);
  EXPECT_NEAR(s.finalCost, c.finalCost, 1e-4 * c.finalCost);
  for (int k = 0; k < DriftedLoop::n; ++k) {
    EXPECT_LT(transformError(sparse.vertex(k), ceres.vertex(k)), 1e-4) << "vertex " << k;
    EXPECT_EQ(automatic.vertex(k).matrix(), ceres.vertex(k).matrix()) << "vertex " << k;
  }
}
//! Camera \e k of a run round a circle, a lap every 20 keyframes (CircleRun.h).
hslam::SE3d circleCamera(int k, double drift)
{
  return hslam_test::circleCamera(k, 20, drift);
}

//! How far the map's relative pose of keyframes \e a and \e b is from the truth's (norm of the SE(3) log).
double relativeError(const hslam::GlobalMap &map, int a, int b)
{
  const hslam::SE3d estimated = map.find(a)->cMw * map.find(b)->cMw.inverse();
  const hslam::SE3d truth = circleCamera(a, 0.) * circleCamera(b, 0.).inverse();
  return (estimated * truth.inverse()).log().norm();
}

TEST(LoopCorrection, EachLoopIsKeptAsOneEdgeThatStillHoldsAtTheNextCorrection)
{
  // Two laps of 20 keyframes whose odometry drifts, the last 3 in the window. A loop is one measured similarity: the
  // graph of later corrections keeps one edge for it (not one per pair of its two sides' keyframes, which made the
  // graph of a long run fill in), and that edge, weighted as any other, must still hold the first loop closed when a
  // second one is corrected.
  constexpr int kStored = 40, kWindow = 3;
  constexpr double kDrift = 3e-3;
  hslam::GlobalMap map;
  std::map<int, hslam::SE3d> window;
  for (int k = 0; k < kStored + kWindow; ++k) {
    if (k < kStored) {
      hslam::GlobalKeyframe g;
      g.id = k;
      g.cMw = circleCamera(k, kDrift);
      map.add(g); // (returns whether it culled a keyframe: no points here, none)
    } else {
      window[k] = circleCamera(k, kDrift);
    }
    if (k > 0) {
      hslam::PosePoseEdge e;
      e.from = k - 1;
      e.to = k;
      e.toMfrom = circleCamera(k, kDrift) * circleCamera(k - 1, kDrift).inverse();
      map.addPosePoseEdge(e);
    }
  }
  auto correct = [&](int keyframe, int candidate, std::vector<hslam::PoseGraphEdge> &constraints) {
    hslam::DetectedLoop loop;
    loop.keyframe = keyframe;
    loop.candidate = candidate;
    loop.SkeyframeCandidate = Sim3d(circleCamera(keyframe, 0.) * circleCamera(candidate, 0.).inverse(), 1.);
    std::vector<std::pair<int, Sim3d>> solution;
    if (!hslam::solveLoopCorrection(map, 0, window, constraints, loop, solution)) {
      return false;
    }
    for (const auto &s : solution) {
      map.applySimilarity(s.first, s.second);
    }
    return true;
  };
  std::vector<hslam::PoseGraphEdge> constraints;
  const double before = relativeError(map, 39, 19);
  ASSERT_TRUE(correct(39, 19, constraints));
  const double corrected = relativeError(map, 39, 19);
  ASSERT_EQ(constraints.size(), 1u);
  EXPECT_EQ(constraints[0].i, 19);
  EXPECT_EQ(constraints[0].j, 39);
  EXPECT_TRUE(constraints[0].sqrtInformation.isIdentity()); // an ordinary edge (solveLoopCorrection)
  ASSERT_TRUE(correct(30, 10, constraints));
  ASSERT_EQ(constraints.size(), 2u);
  const double after = relativeError(map, 39, 19);
  std::printf("loop 39-19: error %.4f before, %.4f corrected, %.4f after the loop 30-10 (which: %.4f)\n", before,
              corrected, after, relativeError(map, 30, 10));
  EXPECT_LT(corrected, 0.1 * before);
  EXPECT_LT(after, 0.1 * before);
  EXPECT_LT(relativeError(map, 30, 10), 0.1 * before);
}

//! A run of \e stored keyframes round a circle of 60 places, the last 3 in the window, whose odometry drifts from
//! keyframe \e driftFrom on (the ones before: reconciled, as earlier loops leave them). Each keyframe is joined to the
//! one before at the stored relative pose; with \e lapLinked also to its place and the two beside it on the lap
//! before, at the true relative pose (what re-used points measure).
struct LapRun {
  static constexpr int kPlaces = 60, kWindow = 3;
  static constexpr double kDrift = 2e-3;
  hslam::GlobalMap map;
  std::map<int, hslam::SE3d> window;
  int driftFrom;

  static hslam::SE3d truth(int k) { return hslam_test::circleCamera(k, kPlaces, 0.); }
  //! The odometry's pose: the camera centre drifted along z by kDrift a keyframe from \e driftFrom on.
  hslam::SE3d odometry(int k) const
  {
    return truth(k) *
           hslam::SE3d(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0., 0., -kDrift * std::max(0, k - driftFrom)));
  }
  void link(int from, int to, const hslam::SE3d &toMfrom)
  {
    hslam::PosePoseEdge e;
    e.from = from;
    e.to = to;
    e.toMfrom = toMfrom;
    map.addPosePoseEdge(e);
  }
  LapRun(int stored, bool lapLinked, int driftFrom_) : driftFrom(driftFrom_)
  {
    for (int k = 0; k < stored + kWindow; ++k) {
      if (k < stored) {
        hslam::GlobalKeyframe g;
        g.id = k;
        g.cMw = odometry(k);
        map.add(g);
      } else {
        window[k] = odometry(k);
      }
      if (k > 0) {
        link(k - 1, k, odometry(k) * odometry(k - 1).inverse());
      }
      for (int d = -1; d <= 1 && lapLinked; ++d) {
        if (k - kPlaces + d >= 0) {
          link(k - kPlaces + d, k, truth(k) * truth(k - kPlaces + d).inverse());
        }
      }
    }
  }
  //! The error of the relative pose of \e a and \e b before any correction.
  double errorBefore(int a, int b) const
  {
    return transformError(Sim3d(odometry(a) * odometry(b).inverse(), 1.), Sim3d(truth(a) * truth(b).inverse(), 1.));
  }
  //! Solve the loop from keyframe \e keyframe to its place on the first lap, bending at most \e maxFree keyframes.
  std::vector<std::pair<int, Sim3d>> correct(int keyframe, size_t maxFree) const
  {
    hslam::DetectedLoop loop;
    loop.keyframe = keyframe;
    loop.candidate = keyframe % kPlaces;
    loop.SkeyframeCandidate = Sim3d(truth(keyframe) * truth(loop.candidate).inverse(), 1.);
    std::vector<hslam::PoseGraphEdge> constraints;
    std::vector<std::pair<int, Sim3d>> solution;
    EXPECT_TRUE(hslam::solveLoopCorrection(map, 0, window, constraints, loop, solution, {}, maxFree));
    return solution;
  }
};

//! The solution's similarity of keyframe \e id.
Sim3d solved(const std::vector<std::pair<int, Sim3d>> &solution, int id)
{
  for (const auto &s : solution) {
    if (s.first == id) {
      return s.second;
    }
  }
  ADD_FAILURE() << "keyframe " << id << " not in the solution";
  return Sim3d();
}

//! Error of the solved relative pose of \e a and \e b against the truth.
double solvedError(const std::vector<std::pair<int, Sim3d>> &solution, int a, int b)
{
  const Sim3d truth(LapRun::truth(a) * LapRun::truth(b).inverse(), 1.);
  return transformError(solved(solution, a) * solved(solution, b).inverse(), truth);
}

TEST(LoopCorrection, AMapTiedLapAfterLapBendsItsNewestKeyframesAndMovesItsPastAsOne)
{
  // 5 laps of 60 keyframes, each tied to the lap before, the odometry drifting since keyframe 200. Held to its 100
  // newest keyframes, the correction must move the 200 older ones as one (their relative poses unchanged) and still
  // close the loop about as well as bending them all.
  const LapRun run(300, true, 200);
  const int query = 299, candidate = 299 % LapRun::kPlaces;
  const auto all = run.correct(query, 100000), held = run.correct(query, 100);
  ASSERT_EQ(all.size(), 300u);
  ASSERT_EQ(held.size(), 300u);
  const double before = run.errorBefore(query, candidate);
  std::printf("loop %d-%d: error %.4f before, %.4f bending all, %.4f bending the newest 100\n", query, candidate,
              before, solvedError(all, query, candidate), solvedError(held, query, candidate));
  EXPECT_LT(solvedError(all, query, candidate), 0.1 * before);
  EXPECT_LT(solvedError(held, query, candidate), 0.1 * before);
  // The past (keyframes 0-199) moved as one: its relative poses are the stored ones; bending all changes them.
  const auto storedRelative = [&](int a, int b) {
    return Sim3d(run.map.find(a)->cMw, 1.) * Sim3d(run.map.find(b)->cMw, 1.).inverse();
  };
  EXPECT_LT(transformError(solved(held, 0) * solved(held, 199).inverse(), storedRelative(0, 199)), 1e-9);
  EXPECT_GT(transformError(solved(all, 0) * solved(all, 199).inverse(), storedRelative(0, 199)), 1e-6);
  // The newest keyframes bent: not the rigid motion of the past.
  EXPECT_GT(transformError(solved(held, 200) * solved(held, 299).inverse(), storedRelative(200, 299)), 1e-6);
}

TEST(LoopCorrection, ALongLoopHangingByItsChainAloneBendsItsWholeSpan)
{
  // One long loop, nothing else tying its start to its end: however large, the whole span bends, as without a cap.
  const LapRun run(300, false, 0);
  const auto all = run.correct(299, 100000), capped = run.correct(299, 100);
  ASSERT_EQ(all.size(), capped.size());
  for (size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].first, capped[i].first);
    EXPECT_LT(transformError(all[i].second, capped[i].second), 1e-12) << "keyframe " << all[i].first;
  }
  EXPECT_LT(solvedError(capped, 299, 59), 0.1 * run.errorBefore(299, 59));
}
} // namespace

TEST_P(PoseGraphSolvers, SolutionDoesNotDependOnInsertionOrderOrHeapLayout)
{
  // The drifted loop built twice, vertices added in opposite orders with other allocations in between, stopped
  // after 3 iterations (not converged): bit-identical vertices (the global bundle adjustment's solution was not:
  // Ceres orders an elimination group's blocks by address; this guards the pose graph against the same).
  const DriftedLoop loop;
  std::vector<std::unique_ptr<std::vector<char>>> clutter;
  auto solve = [&](bool reversed) {
    auto graph = std::make_unique<hslam::PoseGraph>();
    Sim3d chained = loop.truth[0];
    std::vector<Sim3d> start(DriftedLoop::n);
    start[0] = chained;
    for (int k = 1; k < DriftedLoop::n; ++k) {
      chained =
          loop.D * loop.truth[static_cast<size_t>(k)] * loop.truth[static_cast<size_t>(k - 1)].inverse() * chained;
      start[static_cast<size_t>(k)] = chained;
    }
    for (int j = 0; j < DriftedLoop::n; ++j) {
      const int k = reversed ? DriftedLoop::n - 1 - j : j;
      graph->addVertex(k, start[static_cast<size_t>(k)], k == 0);
      clutter.push_back(std::make_unique<std::vector<char>>(static_cast<size_t>(40 + 24 * (j % 7))));
    }
    for (int k = 1; k < DriftedLoop::n; ++k) {
      hslam::PoseGraphEdge e;
      e.i = k - 1;
      e.j = k;
      e.Sji = loop.truth[static_cast<size_t>(k)] * loop.truth[static_cast<size_t>(k - 1)].inverse();
      graph->addEdge(e);
    }
    hslam::PoseGraphEdge closing;
    closing.i = DriftedLoop::n - 1;
    closing.j = 0;
    closing.Sji = loop.truth[0] * loop.truth[static_cast<size_t>(DriftedLoop::n - 1)].inverse();
    graph->addEdge(closing);
    EXPECT_TRUE(graph->optimize(3, GetParam()).usable);
    return graph;
  };
  const std::unique_ptr<hslam::PoseGraph> a = solve(false);
  const std::unique_ptr<hslam::PoseGraph> b = solve(true);
  int differing = 0;
  for (int k = 0; k < DriftedLoop::n; ++k) {
    differing += a->vertex(k).matrix() == b->vertex(k).matrix() ? 0 : 1;
  }
  EXPECT_EQ(differing, 0);
}
