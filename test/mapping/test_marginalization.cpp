/*
 * H-SLAM for ViSP.
 */
// Marginalisation prior: Schur complement and FEJ algebra, the window's gauge before / after marginalising, and what
// becomes of points kept on a depth prior when they leave the window.
#include "HSlamTestData.h"
#include "WindowTestScene.h"

#include "mapping/MarginalizationPrior.h"
#include "mapping/WindowOptimizer.h"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <cmath>
#include <random>

using namespace hslam;
using hslam_test::TestScene;

namespace
{
//! Eigenvalues of a Jacobi-scaled Hessian below this fraction of the largest count as its null space.
constexpr double kNullRelativeEigenvalue = 1e-9;

//! Eigenvalues of D^-1/2 H D^-1/2 (D = diag H, zero rows left out), ascending.
Eigen::VectorXd scaledEigenvalues(const Eigen::MatrixXd &H, Eigen::MatrixXd *vectors = nullptr,
                                  Eigen::VectorXd *scale = nullptr)
{
  Eigen::VectorXd s(H.rows());
  for (Eigen::Index i = 0; i < H.rows(); ++i) {
    s[i] = H(i, i) > 0. ? 1. / std::sqrt(H(i, i)) : 1.;
  }
  const Eigen::MatrixXd Hs = s.asDiagonal() * H * s.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(Hs);
  if (vectors) {
    *vectors = eig.eigenvectors();
  }
  if (scale) {
    *scale = s;
  }
  return eig.eigenvalues();
}

int nullity(const Eigen::VectorXd &eigenvalues)
{
  int n = 0;
  for (Eigen::Index i = 0; i < eigenvalues.size(); ++i) {
    n += eigenvalues[i] < kNullRelativeEigenvalue * eigenvalues.maxCoeff();
  }
  return n;
}

std::vector<KeyframeState> randomStates(int n, std::mt19937 &rng)
{
  std::normal_distribution<double> g(0., 0.1);
  std::vector<KeyframeState> s(static_cast<size_t>(n));
  for (auto &x : s) {
    Eigen::Matrix<double, 6, 1> xi;
    for (int k = 0; k < 6; ++k) {
      xi[k] = g(rng);
    }
    x.cMw = SE3d::exp(xi);
    x.a = g(rng);
    x.b = 10. * g(rng);
  }
  return s;
}
} // namespace

TEST(MarginalizationPrior, SchurComplementAndFirstEstimateTransfer)
{
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0., 1.);
  constexpr int n = 3, dim = n * kFrameDims;
  Eigen::MatrixXd J(40, dim);
  for (Eigen::Index i = 0; i < J.size(); ++i) {
    J.data()[i] = g(rng);
  }
  Eigen::VectorXd r(40);
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    r[i] = g(rng);
  }
  const Eigen::MatrixXd H = J.transpose() * J;
  const Eigen::VectorXd b = J.transpose() * r;
  std::vector<KeyframeState> states = randomStates(n, rng);

  MarginalizationPrior prior;
  for (int i = 0; i < n; ++i) {
    prior.addFrame();
  }
  prior.add(H, b, states);
  // At the linearisation point the prior is exactly the quadratic added.
  EXPECT_NEAR((prior.gradient(states) - b).norm(), 0., 1e-12);
  EXPECT_NEAR(prior.energy(states), 0., 1e-12);

  // FEJ: information computed at a moved state is expressed at the first linearisation point: b0 = g - H D.
  std::vector<KeyframeState> moved = states;
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.01, -0.02, 0.005, 0.003, 0.001, -0.002;
  moved[1].cMw = SE3d::exp(xi) * moved[1].cMw;
  moved[1].a += 0.01;
  const Eigen::VectorXd D = prior.deviation(moved);
  EXPECT_NEAR((D.segment<6>(kFrameDims) - xi).norm(), 0., 1e-12);
  EXPECT_NEAR(D[kFrameDims + 6], 0.01, 1e-15);
  prior.add(H, b, moved);
  EXPECT_NEAR((prior.gradient(moved) - (b + H * D + b)).norm(), 0., 1e-9 * b.norm());

  // Schur complement of keyframe 1 against the explicit formula.
  const Eigen::MatrixXd Hp = prior.H();
  const Eigen::VectorXd bp = prior.b();
  std::vector<int> keep = {0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23};
  Eigen::MatrixXd Hkk(16, 16), Hkm(16, 8);
  Eigen::VectorXd bk(16);
  for (int i = 0; i < 16; ++i) {
    for (int j = 0; j < 16; ++j) {
      Hkk(i, j) = Hp(keep[static_cast<size_t>(i)], keep[static_cast<size_t>(j)]);
    }
    Hkm.row(i) = Hp.block(keep[static_cast<size_t>(i)], 8, 1, 8);
    bk[i] = bp[keep[static_cast<size_t>(i)]];
  }
  const Eigen::MatrixXd Hmm = Hp.block(8, 8, 8, 8);
  const Eigen::MatrixXd expectedH = Hkk - Hkm * Hmm.inverse() * Hkm.transpose();
  const Eigen::VectorXd expectedB = bk - Hkm * Hmm.inverse() * bp.segment(8, 8);
  prior.removeFrame(1, false);
  ASSERT_EQ(prior.numFrames(), 2);
  EXPECT_NEAR((prior.H() - expectedH).norm(), 0., 1e-9 * expectedH.norm());
  EXPECT_NEAR((prior.b() - expectedB).norm(), 0., 1e-9 * expectedB.norm());
  // Dropping a fixed (gauge) keyframe just removes its rows.
  const Eigen::MatrixXd before = prior.H();
  prior.removeFrame(0, true);
  EXPECT_NEAR((prior.H() - before.bottomRightCorner(8, 8)).norm(), 0., 1e-12);
}

TEST(WindowMarginalization, GaugeNullSpaceAndPriorAfterMarginalizingTheOldestKeyframe)
{
  TestScene scene;
  constexpr int kKeyframes = 6;
  constexpr unsigned int kFrameStep = 4;
  constexpr int kPoints = 250;
  std::vector<KeyframePtr> kfs;
  WindowOptimizer opt(scene.params);
  for (int k = 0; k < kKeyframes; ++k) {
    kfs.push_back(scene.makeKeyframe(static_cast<unsigned int>(k) * kFrameStep, k, kPoints));
    opt.addKeyframe(kfs.back());
  }
  // At the ground truth (a_ji = 1): 7 gauge directions (pose, scale) + the common gain a + the common offset b.
  Eigen::MatrixXd H;
  Eigen::VectorXd b;
  opt.reducedSystem(H, b);
  const Eigen::VectorXd eigFull = scaledEigenvalues(H);
  std::printf("full window: smallest scaled eigenvalues %.2g %.2g ... [9] %.2g [10] %.2g, max %.2g\n", eigFull[0],
              eigFull[1], eigFull[8], eigFull[9], eigFull.maxCoeff());
  EXPECT_EQ(nullity(eigFull), 9);

  const OptimizationSummary s0 = opt.optimize(10);
  ASSERT_GT(s0.iterations, 0);
  const SE3d gaugeCMw = kfs[0]->frame->cMw;
  opt.marginalizeKeyframe(0);
  EXPECT_FALSE(kfs[0]->inWindow);
  EXPECT_EQ(opt.numKeyframes(), kKeyframes - 1);
  int marginalized = 0;
  for (const MapPoint &p : kfs[0]->points) {
    marginalized += p.status == PointStatus::marginalized;
  }
  EXPECT_EQ(marginalized, static_cast<int>(kfs[0]->points.size()));

  // The prior: symmetric, positive semidefinite, and only the scale is free (keyframe 0 was the pose and affine
  // gauge; what its points said about the others is relative to it).
  const MarginalizationPrior &prior = opt.prior();
  ASSERT_TRUE(prior.hasInformation());
  const Eigen::MatrixXd &Hp = prior.H();
  EXPECT_LT((Hp - Hp.transpose()).norm(), 1e-12 * Hp.norm());
  Eigen::MatrixXd V;
  Eigen::VectorXd sc;
  const Eigen::VectorXd eigPrior = scaledEigenvalues(Hp, &V, &sc);
  std::printf("prior: smallest scaled eigenvalues %.2g %.2g %.2g, max %.2g\n", eigPrior[0], eigPrior[1], eigPrior[2],
              eigPrior.maxCoeff());
  EXPECT_GT(eigPrior.minCoeff(), -kNullRelativeEigenvalue * eigPrior.maxCoeff());
  EXPECT_EQ(nullity(eigPrior), 1);
  // ... and that null direction is the scale about keyframe 0's centre.
  Eigen::VectorXd scaleDir = Eigen::VectorXd::Zero(Hp.rows());
  for (int k = 1; k < kKeyframes; ++k) {
    scaleDir.segment<3>((k - 1) * kFrameDims) =
        (kfs[static_cast<size_t>(k)]->frame->cMw * gaugeCMw.inverse()).translation();
  }
  const Eigen::VectorXd scaledDir = (scaleDir.array() / sc.array()).matrix().normalized();
  EXPECT_GT(std::fabs(scaledDir.dot(V.col(0))), 0.99);

  // New keyframe, perturbed, and optimise: the window keeps its gauge through the prior.
  kfs.push_back(scene.makeKeyframe(kKeyframes * kFrameStep, kKeyframes, kPoints));
  Eigen::Matrix<double, 6, 1> xi;
  xi << 0.01, -0.005, 0.008, 0.004, -0.003, 0.002;
  kfs.back()->frame->cMw = SE3d::exp(xi) * kfs.back()->frame->cMw;
  opt.addKeyframe(kfs.back());
  opt.reducedSystem(H, b, true);
  EXPECT_EQ(nullity(scaledEigenvalues(H)), 1);
  const OptimizationSummary s1 = opt.optimize(20);
  std::printf("after marginalisation: %d its, energy %.1f -> %.1f\n", s1.iterations, s1.initialEnergy, s1.finalEnergy);
  EXPECT_LT(s1.finalEnergy, s1.initialEnergy);
  // The RMSE the mapper logs and checks comes from the photometric part alone: the prior's energy is relative to its
  // linearisation point and may be negative (it made the logged RMSE NaN on long runs).
  EXPECT_TRUE(std::isfinite(s1.finalPhotometricEnergy));
  EXPECT_GT(s1.finalPhotometricEnergy, 0.);
  // Scale of the window from its points, then every pose relative to the (marginalised) gauge keyframe.
  std::vector<double> ratios;
  for (size_t k = 1; k < kfs.size(); ++k) {
    for (const MapPoint &p : kfs[k]->points) {
      if (p.status == PointStatus::active) {
        ratios.push_back((1. / scene.scene.depthAt(p.u, p.v, static_cast<unsigned int>(kfs[k]->frame->id))) / p.idepth);
      }
    }
  }
  std::nth_element(ratios.begin(), ratios.begin() + static_cast<long>(ratios.size() / 2), ratios.end());
  const double scale = ratios[ratios.size() / 2];
  double maxRot = 0., maxTrans = 0.;
  for (size_t k = 1; k < kfs.size(); ++k) {
    SE3d est = kfs[k]->frame->cMw * gaugeCMw.inverse();
    est.translation() /= scale;
    const SE3d gt = scene.trueCMw(kfs[k]->frame->id) * scene.trueCMw(0).inverse();
    double r, t;
    hslam_test::poseError(est, gt, r, t);
    maxRot = std::max(maxRot, r);
    maxTrans = std::max(maxTrans, t);
  }
  std::printf("after marginalisation: scale %.4f, max error %.4f deg %.5f m\n", scale, maxRot, maxTrans);
  EXPECT_NEAR(scale, 1., 0.01);
  EXPECT_LT(maxRot, 0.03);
  EXPECT_LT(maxTrans, 0.0015);
}

namespace
{
//! Flags the first \e count active points of \e kf as kept on a depth prior at their own inverse depth.
void flagOnPrior(Keyframe &kf, size_t count)
{
  for (size_t i = 0; i < count && i < kf.points.size(); ++i) {
    MapPoint &p = kf.points[i];
    p.depthFromPrior = true;
    p.idepthPrior = p.idepth;
    p.idepthPriorWeight = 1. / (p.idepth * p.idepth);
  }
}

//! Four keyframes \e frameStep frames apart (0: all at the first frame's pose) added to \e opt.
std::vector<KeyframePtr> addFourKeyframes(WindowOptimizer &opt, const TestScene &scene, unsigned int frameStep,
                                          int points)
{
  std::vector<KeyframePtr> kfs;
  for (int k = 0; k < 4; ++k) {
    kfs.push_back(scene.makeKeyframe(static_cast<unsigned int>(k) * frameStep, k, points));
    opt.addKeyframe(kfs.back());
  }
  return kfs;
}

//! Status counts of the first \e count points of \e kf and of the others.
void countStatuses(const Keyframe &kf, size_t count, int &flaggedOutliers, int &othersMarginalized)
{
  flaggedOutliers = othersMarginalized = 0;
  for (size_t i = 0; i < kf.points.size(); ++i) {
    if (i < count) {
      flaggedOutliers += kf.points[i].status == PointStatus::outlier;
    } else {
      othersMarginalized += kf.points[i].status == PointStatus::marginalized;
    }
  }
}
} // namespace

TEST(WindowMarginalization, PointsOnADepthPriorAreStoredOnlyOnceTheWindowMeasuredTheirDepth)
{
  // A point activated on a depth prior while the camera turned in place (LocalMapper, mapper.rotationFlowPx) leaves
  // the window as an outlier unless an optimisation found its depth measured (photometric inverse-depth Hessian at
  // least mapper.minIdepthHessianActivate): a guessed depth must not enter the global map.
  TestScene scene;
  constexpr int kPoints = 150;
  constexpr size_t kFlagged = 20;
  int flaggedOutliers = 0, othersMarginalized = 0;

  // Keyframes 4 frames apart: every depth is measured, so an optimisation clears the flags.
  {
    WindowOptimizer opt(scene.params);
    const std::vector<KeyframePtr> kfs = addFourKeyframes(opt, scene, 4u, kPoints);
    flagOnPrior(*kfs[0], kFlagged);
    opt.optimize(3);
    int stillFlagged = 0;
    for (const MapPoint &p : kfs[0]->points) {
      stillFlagged += p.depthFromPrior ? 1 : 0;
    }
    EXPECT_EQ(stillFlagged, 0);
    opt.marginalizeKeyframe(0);
    countStatuses(*kfs[0], kFlagged, flaggedOutliers, othersMarginalized);
    EXPECT_EQ(flaggedOutliers, 0);
  }
  // The same keyframes marginalised before any optimisation saw them: the flagged points are dropped, not the others.
  {
    WindowOptimizer opt(scene.params);
    const std::vector<KeyframePtr> kfs = addFourKeyframes(opt, scene, 4u, kPoints);
    flagOnPrior(*kfs[0], kFlagged);
    opt.marginalizeKeyframe(0);
    countStatuses(*kfs[0], kFlagged, flaggedOutliers, othersMarginalized);
    EXPECT_EQ(flaggedOutliers, static_cast<int>(kFlagged));
    EXPECT_EQ(othersMarginalized, static_cast<int>(kfs[0]->points.size() - kFlagged));
  }
  // Four keyframes at the same pose (a camera turning about its centre, without the turn): no baseline, no depth
  // measured, the flags stay through an optimisation and the flagged points are dropped.
  {
    WindowOptimizer opt(scene.params);
    const std::vector<KeyframePtr> kfs = addFourKeyframes(opt, scene, 0u, kPoints);
    flagOnPrior(*kfs[0], kFlagged);
    opt.optimize(3);
    int stillFlagged = 0;
    for (size_t i = 0; i < kFlagged; ++i) {
      stillFlagged += kfs[0]->points[i].depthFromPrior ? 1 : 0;
    }
    EXPECT_EQ(stillFlagged, static_cast<int>(kFlagged));
    opt.marginalizeKeyframe(0);
    countStatuses(*kfs[0], kFlagged, flaggedOutliers, othersMarginalized);
    EXPECT_EQ(flaggedOutliers, static_cast<int>(kFlagged));
  }
}
