/*
 * H-SLAM for ViSP.
 */
// Analytic Jacobians of the photometric residual against central differences.
#include "HSlamTestData.h"

#include "mapping/PhotometricResidual.h"

#include <gtest/gtest.h>

#include <array>
#include <functional>

using namespace hslam;

namespace
{
constexpr int kWidth = 320;
constexpr int kHeight = 240;
//! I = c + alpha u + beta v + gamma u v: bilinear interpolation and central-difference gradients are EXACT on it,
//! so the analytic Jacobian (interpolated gradient) and numeric differences must agree to rounding.
constexpr double kC = 40., kAlpha = 0.25, kBeta = -0.15, kGamma = 0.002;
//! Central-difference step: pose (m, rad), affine, inverse depth. Large enough for the float image look-ups.
constexpr double kStep = 1e-3;
constexpr double kRelTol = 2e-3;
//! Float image look-ups round intensities (~200) to ~1e-5: over 2 kStep that is ~0.01 per unit of derivative,
//! so derivatives are compared relative to at least this magnitude (grey levels per unit).
constexpr double kMinDerivativeScale = 10.;

ImagePyramid makeImage(const PinholeIntrinsics &K)
{
  vpImage<float> I(kHeight, kWidth);
  for (int v = 0; v < kHeight; ++v) {
    for (int u = 0; u < kWidth; ++u) {
      I[v][u] = static_cast<float>(kC + kAlpha * u + kBeta * v + kGamma * u * v);
    }
  }
  ImagePyramid pyr;
  pyr.build(I, K, 1, 1);
  return pyr;
}

struct ResidualSetup {
  PinholeIntrinsics K{250., 255., 159.5, 119.5};
  PhotometricSettings settings;
  ImagePyramid target = makeImage(K);
  SE3d hostMw, targetMw;
  double aH = 0.1, bH = 3., aT = -0.05, bT = -2., eH = 1.2, eT = 0.9;
  std::array<float, kPatternSize> patch{}, weight{};
  PointObservation obs;

  ResidualSetup()
  {
    settings.K = K;
    settings.huberThreshold = 1e9; // residuals are large here; keep the pure least-squares weights
    settings.outlierEnergy = 1e18;
    Eigen::Matrix<double, 6, 1> xi;
    xi << 0.1, -0.05, 0.2, 0.02, -0.03, 0.01;
    hostMw = SE3d::exp(xi);
    xi << 0.05, 0.02, 0.1, -0.01, 0.04, 0.02;
    targetMw = SE3d::exp(xi);
    for (int k = 0; k < kPatternSize; ++k) {
      patch[static_cast<size_t>(k)] = 50.f + 7.f * static_cast<float>(k);
      weight[static_cast<size_t>(k)] = 1.f;
    }
    obs.u = 140.3;
    obs.v = 101.7;
    obs.idepth = 0.45;
    obs.patch = patch.data();
    obs.weight = weight.data();
  }

  PatternLinearization eval(const SE3d &h, double ah, double bh, const SE3d &t, double at, double bt,
                            double idepth) const
  {
    FramePairPrecalc pair;
    pair.set(h, ah, bh, eH, t, at, bt, eT);
    PointObservation o = obs;
    o.idepth = idepth;
    PatternLinearization lin;
    double e = 0.;
    EXPECT_EQ(evaluatePattern(settings, target.level(0), pair, o, e, &lin), ResidualState::inlier);
    return lin;
  }
};

Eigen::Matrix<double, kPatternSize, 1> residuals(const PatternLinearization &lin)
{
  Eigen::Matrix<double, kPatternSize, 1> r;
  for (int k = 0; k < kPatternSize; ++k) {
    r[k] = lin.r[static_cast<size_t>(k)];
  }
  return r;
}

//! Central difference of the pattern residuals for a perturbation f(+h) / f(-h).
Eigen::Matrix<double, kPatternSize, 1> numeric(const std::function<PatternLinearization(double)> &f)
{
  return (residuals(f(kStep)) - residuals(f(-kStep))) / (2. * kStep);
}

void expectClose(const Eigen::Matrix<double, kPatternSize, 1> &analytic,
                 const Eigen::Matrix<double, kPatternSize, 1> &num, const char *what)
{
  const double scale = std::max(kMinDerivativeScale, num.norm());
  EXPECT_LT((analytic - num).norm(), kRelTol * scale)
      << what << "\nanalytic " << analytic.transpose() << "\nnumeric  " << num.transpose();
}
} // namespace

TEST(PhotometricResidual, RelativePoseAndInverseDepthJacobians)
{
  ResidualSetup s;
  const PatternLinearization lin = s.eval(s.hostMw, s.aH, s.bH, s.targetMw, s.aT, s.bT, s.obs.idepth);
  for (int k = 0; k < 6; ++k) {
    // Perturbing the target's absolute pose on the left perturbs T_th on the left by the same twist.
    const auto f = [&](double h) {
      Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
      d[k] = h;
      return s.eval(s.hostMw, s.aH, s.bH, SE3d::exp(d) * s.targetMw, s.aT, s.bT, s.obs.idepth);
    };
    expectClose(lin.J.col(k), numeric(f), "relative pose");
  }
  const auto fr = [&](double h) { return s.eval(s.hostMw, s.aH, s.bH, s.targetMw, s.aT, s.bT, s.obs.idepth + h); };
  expectClose(lin.J.col(8), numeric(fr), "inverse depth");
}

TEST(PhotometricResidual, HostPoseJacobianThroughAdjoint)
{
  ResidualSetup s;
  const PatternLinearization lin = s.eval(s.hostMw, s.aH, s.bH, s.targetMw, s.aT, s.bT, s.obs.idepth);
  FramePairPrecalc pair;
  pair.set(s.hostMw, s.aH, s.bH, s.eH, s.targetMw, s.aT, s.bT, s.eT);
  const Eigen::Matrix<double, kPatternSize, kFrameDims> Jhost = lin.J.leftCols<kFrameDims>() * pair.dRelative_dHost;
  for (int k = 0; k < 6; ++k) {
    const auto f = [&](double h) {
      Eigen::Matrix<double, 6, 1> d = Eigen::Matrix<double, 6, 1>::Zero();
      d[k] = h;
      return s.eval(SE3d::exp(d) * s.hostMw, s.aH, s.bH, s.targetMw, s.aT, s.bT, s.obs.idepth);
    };
    expectClose(Jhost.col(k), numeric(f), "host pose");
  }
}

TEST(PhotometricResidual, AffineJacobiansOfHostAndTarget)
{
  ResidualSetup s;
  const PatternLinearization lin = s.eval(s.hostMw, s.aH, s.bH, s.targetMw, s.aT, s.bT, s.obs.idepth);
  FramePairPrecalc pair;
  pair.set(s.hostMw, s.aH, s.bH, s.eH, s.targetMw, s.aT, s.bT, s.eT);
  const Eigen::Matrix<double, kPatternSize, kFrameDims> Jh = lin.J.leftCols<kFrameDims>() * pair.dRelative_dHost;
  const Eigen::Matrix<double, kPatternSize, kFrameDims> Jt = lin.J.leftCols<kFrameDims>() * pair.dRelative_dTarget;
  const auto fah = [&](double h) { return s.eval(s.hostMw, s.aH + h, s.bH, s.targetMw, s.aT, s.bT, s.obs.idepth); };
  const auto fbh = [&](double h) { return s.eval(s.hostMw, s.aH, s.bH + h, s.targetMw, s.aT, s.bT, s.obs.idepth); };
  const auto fat = [&](double h) { return s.eval(s.hostMw, s.aH, s.bH, s.targetMw, s.aT + h, s.bT, s.obs.idepth); };
  const auto fbt = [&](double h) { return s.eval(s.hostMw, s.aH, s.bH, s.targetMw, s.aT, s.bT + h, s.obs.idepth); };
  expectClose(Jh.col(6), numeric(fah), "a host");
  expectClose(Jh.col(7), numeric(fbh), "b host");
  expectClose(Jt.col(6), numeric(fat), "a target");
  expectClose(Jt.col(7), numeric(fbt), "b target");
  // The target-pose block of the chain is the identity (relative pose perturbed by the target's twist).
  EXPECT_NEAR((pair.dRelative_dTarget.topLeftCorner<6, 6>() - Eigen::Matrix<double, 6, 6>::Identity()).norm(), 0.,
              1e-15);
}

TEST(PhotometricResidual, OutOfBoundsAndOutlierStates)
{
  ResidualSetup s;
  FramePairPrecalc pair;
  pair.set(s.hostMw, s.aH, s.bH, s.eH, s.targetMw, s.aT, s.bT, s.eT);
  double e = 0.;
  PointObservation far = s.obs;
  far.u = 2.; // pattern pixel at u = 0 lands near the border of the target too
  far.idepth = -0.1;
  EXPECT_EQ(evaluatePattern(s.settings, s.target.level(0), pair, far, e, nullptr), ResidualState::outOfBounds);
  PhotometricSettings strict = s.settings;
  strict.outlierEnergy = 1.; // residuals here are tens of grey levels
  EXPECT_EQ(evaluatePattern(strict, s.target.level(0), pair, s.obs, e, nullptr), ResidualState::outlier);
  EXPECT_DOUBLE_EQ(e, strict.outlierEnergy);
}
