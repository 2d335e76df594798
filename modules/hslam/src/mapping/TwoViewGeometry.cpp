/*
 * H-SLAM for ViSP.
 */
#include "mapping/TwoViewGeometry.h"

#include "math/SO3.h"

#include <Eigen/Dense>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>

namespace hslam
{
namespace
{
//! Chi-square 95 % bounds (ORB-SLAM2 Initializer): 1 DOF for a point-to-line distance, 2 DOF for a transfer error.
constexpr double kChi2OneDof95 = 3.841;
constexpr double kChi2TwoDof95 = 5.991;
//! Below this |w| of the homogeneous DLT solution the point is at infinity (normalised coordinates).
constexpr double kMinHomogeneousW = 1e-12;
/*!
  ORB-SLAM2 CheckRT: a point whose rays' cosine exceeds this (parallax < ~0.36 deg) has a depth sign that noise
  decides, so it is not rejected for lying behind a camera.
*/
constexpr double kCheiralityMinParallaxCos = 0.99998;
//! Sampson refinement: iterations, numeric step (rad / unit translation), LM damping schedule.
constexpr int kRefineIterations = 15;
constexpr double kRefineNumericStep = 1e-6;
constexpr double kRefineInitialLambda = 1e-4;
constexpr double kRefineLambdaUp = 10.;
constexpr double kRefineLambdaDown = 0.1;
constexpr double kRefineMinRelativeDecrease = 1e-9;
constexpr double kRefineMaxLambda = 1e6;
//! Huber's tuning constant: 95 % efficiency on Gaussian residuals, in units of their standard deviation.
constexpr double kHuberTuning = 1.345;
//! Smallest Huber width, pixels (exact synthetic matches would otherwise give a zero width).
constexpr double kMinHuberPx = 1e-3;
//! Median absolute deviation to standard deviation for Gaussian data.
constexpr double kMadToSigma = 1.4826;
//! Guards the Sampson denominator (zero only for a match on both epipoles).
constexpr double kMinSampsonDenominator = 1e-300;
//! tangentBasis: pick the helper axis least aligned with n (|cos| < this).
constexpr double kMaxHelperAxisCos = 0.9;
constexpr double kRadToDeg = 180. / M_PI;

Eigen::Matrix3d intrinsicsMatrix(const PinholeIntrinsics &K)
{
  Eigen::Matrix3d M;
  M << K.fx, 0., K.cx, 0., K.fy, K.cy, 0., 0., 1.;
  return M;
}

Eigen::Vector2d normalise(const PinholeIntrinsics &K, const Eigen::Vector2d &p)
{
  return {(p.x() - K.cx) / K.fx, (p.y() - K.cy) / K.fy};
}

double reprojErrSq(const PinholeIntrinsics &K, const Eigen::Vector3d &X, const Eigen::Vector2d &p)
{
  const double du = K.fx * X.x() / X.z() + K.cx - p.x();
  const double dv = K.fy * X.y() / X.z() + K.cy - p.y();
  return du * du + dv * dv;
}

//! Orthonormal basis of the plane orthogonal to the unit vector n.
Eigen::Matrix<double, 3, 2> tangentBasis(const Eigen::Vector3d &n)
{
  const Eigen::Vector3d a = std::abs(n.x()) < kMaxHelperAxisCos ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d b1 = n.cross(a).normalized();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = b1;
  B.col(1) = n.cross(b1);
  return B;
}

//! Sampson residual (signed, pixels) of every flagged match for the pixel fundamental matrix F.
void sampsonResiduals(const Eigen::Matrix3d &F, const PixelVector &p1, const PixelVector &p2,
                      const std::vector<int> &index, Eigen::VectorXd &r)
{
  r.resize(static_cast<Eigen::Index>(index.size()));
  for (size_t k = 0; k < index.size(); ++k) {
    const size_t i = static_cast<size_t>(index[k]);
    const Eigen::Vector3d x1(p1[i].x(), p1[i].y(), 1.), x2(p2[i].x(), p2[i].y(), 1.);
    const Eigen::Vector3d l2 = F * x1, l1 = F.transpose() * x2;
    const double denom = l2.x() * l2.x() + l2.y() * l2.y() + l1.x() * l1.x() + l1.y() * l1.y();
    r[static_cast<Eigen::Index>(k)] = x2.dot(l2) / std::sqrt(std::max(denom, kMinSampsonDenominator));
  }
}

//! 1.4826 median |r|: the standard deviation of Gaussian residuals, robust to outliers.
double robustSigma(const Eigen::VectorXd &r)
{
  std::vector<double> a(static_cast<size_t>(r.size()));
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    a[static_cast<size_t>(i)] = std::abs(r[i]);
  }
  std::nth_element(a.begin(), a.begin() + static_cast<std::ptrdiff_t>(a.size() / 2), a.end());
  return kMadToSigma * a[a.size() / 2];
}

double huberCost(const Eigen::VectorXd &r, double k)
{
  double c = 0.;
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    const double a = std::abs(r[i]);
    c += a <= k ? a * a : 2. * k * a - k * k;
  }
  return c;
}
} // namespace

double homographyScore(const Eigen::Matrix3d &H21, const PixelVector &p1, const PixelVector &p2, double sigma,
                       std::vector<unsigned char> &inliers)
{
  const Eigen::Matrix3d H12 = H21.inverse();
  const double invSigmaSq = 1. / (sigma * sigma);
  double score = 0.;
  inliers.assign(p1.size(), 0);
  for (size_t i = 0; i < p1.size(); ++i) {
    const Eigen::Vector3d q2 = H21 * p1[i].homogeneous();
    const Eigen::Vector3d q1 = H12 * p2[i].homogeneous();
    const double chi2In2 = (q2.hnormalized() - p2[i]).squaredNorm() * invSigmaSq;
    const double chi2In1 = (q1.hnormalized() - p1[i]).squaredNorm() * invSigmaSq;
    bool in = true;
    for (const double chi2 : {chi2In1, chi2In2}) {
      if (!(chi2 <= kChi2TwoDof95)) { // also rejects NaN (point mapped to infinity)
        in = false;
      } else {
        score += kChi2TwoDof95 - chi2;
      }
    }
    inliers[i] = in ? 1 : 0;
  }
  return score;
}

double fundamentalScore(const Eigen::Matrix3d &F21, const PixelVector &p1, const PixelVector &p2, double sigma,
                        std::vector<unsigned char> &inliers)
{
  const double invSigmaSq = 1. / (sigma * sigma);
  double score = 0.;
  inliers.assign(p1.size(), 0);
  for (size_t i = 0; i < p1.size(); ++i) {
    const Eigen::Vector3d x1 = p1[i].homogeneous(), x2 = p2[i].homogeneous();
    const Eigen::Vector3d l2 = F21 * x1, l1 = F21.transpose() * x2;
    const double num = x2.dot(l2);
    const double chi2In2 = num * num / (l2.x() * l2.x() + l2.y() * l2.y()) * invSigmaSq;
    const double chi2In1 = num * num / (l1.x() * l1.x() + l1.y() * l1.y()) * invSigmaSq;
    bool in = true;
    for (const double chi2 : {chi2In1, chi2In2}) {
      if (!(chi2 <= kChi2OneDof95)) {
        in = false;
      } else {
        score += kChi2TwoDof95 - chi2;
      }
    }
    inliers[i] = in ? 1 : 0;
  }
  return score;
}

bool triangulateLinear(const Eigen::Vector2d &x1, const Eigen::Vector2d &x2, const Eigen::Matrix3d &R,
                       const Eigen::Vector3d &t, Eigen::Vector3d &X1)
{
  Eigen::Matrix<double, 3, 4> P2;
  P2.leftCols<3>() = R;
  P2.col(3) = t;
  Eigen::Matrix4d A;
  A.row(0) << -1., 0., x1.x(), 0.; // x1 * P1.row(2) - P1.row(0), P1 = [I | 0]
  A.row(1) << 0., -1., x1.y(), 0.;
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d Xh = svd.matrixV().col(3);
  if (std::abs(Xh[3]) < kMinHomogeneousW) {
    return false;
  }
  X1 = Xh.head<3>() / Xh[3];
  return X1.allFinite();
}

MotionCheck checkMotion(const Eigen::Matrix3d &R, const Eigen::Vector3d &t, const PinholeIntrinsics &K,
                        const PixelVector &p1, const PixelVector &p2, const std::vector<unsigned char> &candidates,
                        double maxReprojErrSq)
{
  MotionCheck check;
  const size_t n = p1.size();
  check.good.assign(n, 0);
  check.X1.assign(n, Eigen::Vector3d::Zero());
  check.parallaxDeg.assign(n, 0.);
  const Eigen::Vector3d O2 = -R.transpose() * t; // second camera centre in the first camera
  std::vector<double> parallaxes;
  parallaxes.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!candidates[i]) {
      continue;
    }
    Eigen::Vector3d X1;
    if (!triangulateLinear(normalise(K, p1[i]), normalise(K, p2[i]), R, t, X1)) {
      continue;
    }
    const Eigen::Vector3d ray1 = X1, ray2 = X1 - O2;
    const double cosParallax = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
    const Eigen::Vector3d X2 = R * X1 + t;
    if (cosParallax < kCheiralityMinParallaxCos && (X1.z() <= 0. || X2.z() <= 0.)) {
      continue;
    }
    if (reprojErrSq(K, X1, p1[i]) > maxReprojErrSq || reprojErrSq(K, X2, p2[i]) > maxReprojErrSq) {
      continue;
    }
    check.good[i] = 1;
    check.X1[i] = X1;
    check.parallaxDeg[i] = std::acos(std::min(1., cosParallax)) * kRadToDeg;
    parallaxes.push_back(check.parallaxDeg[i]);
    ++check.numGood;
  }
  if (!parallaxes.empty()) {
    auto mid = parallaxes.begin() + static_cast<std::ptrdiff_t>(parallaxes.size() / 2);
    std::nth_element(parallaxes.begin(), mid, parallaxes.end());
    check.medianParallaxDeg = *mid;
  }
  return check;
}

namespace
{
template <typename FundamentalFn>
double translationDirectionSigmaDeg(const FundamentalFn &fundamental, const Eigen::Matrix3d &R,
                                    const Eigen::Vector3d &t, const PixelVector &p1, const PixelVector &p2,
                                    const std::vector<int> &index, double huberPx)
{
  constexpr int kParams = 5;
  Eigen::VectorXd r, rPlus, rMinus;
  sampsonResiduals(fundamental(R, t, Eigen::Matrix<double, 5, 1>::Zero()), p1, p2, index, r);
  Eigen::MatrixXd J(r.size(), kParams);
  for (int k = 0; k < kParams; ++k) {
    Eigen::Matrix<double, 5, 1> d = Eigen::Matrix<double, 5, 1>::Zero();
    d[k] = kRefineNumericStep;
    sampsonResiduals(fundamental(R, t, d), p1, p2, index, rPlus);
    d[k] = -kRefineNumericStep;
    sampsonResiduals(fundamental(R, t, d), p1, p2, index, rMinus);
    J.col(k) = (rPlus - rMinus) / (2. * kRefineNumericStep);
  }
  Eigen::VectorXd w(r.size());
  for (Eigen::Index i = 0; i < r.size(); ++i) {
    w[i] = std::abs(r[i]) <= huberPx ? 1. : huberPx / std::abs(r[i]);
  }
  const double sigmaR = robustSigma(r);
  const Eigen::Matrix<double, 5, 5> H = J.transpose() * w.asDiagonal() * J;
  // Schur complement of the rotation block: information on the two translation-direction parameters.
  const Eigen::Matrix2d Htt = H.bottomRightCorner<2, 2>() -
                              H.bottomLeftCorner<2, 3>() * H.topLeftCorner<3, 3>().ldlt().solve(
                                                               Eigen::Matrix<double, 3, 2>(H.topRightCorner<3, 2>()));
  const double minInformation = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(Htt).eigenvalues()[0];
  if (!(minInformation > 0.)) {
    return std::numeric_limits<double>::infinity();
  }
  return sigmaR / std::sqrt(minInformation) * kRadToDeg;
}
} // namespace

bool refineRelativePose(Eigen::Matrix3d &R, Eigen::Vector3d &t, const PinholeIntrinsics &K, const PixelVector &p1,
                        const PixelVector &p2, const std::vector<unsigned char> &inliers, double huberPx,
                        double *translationDirSigmaDeg)
{
  std::vector<int> index;
  for (size_t i = 0; i < inliers.size(); ++i) {
    if (inliers[i]) {
      index.push_back(static_cast<int>(i));
    }
  }
  constexpr int kParams = 5; // 3 rotation + 2 translation directions (|t| is a gauge)
  if (static_cast<int>(index.size()) < kParams) {
    return false;
  }
  const Eigen::Matrix3d Kinv = intrinsicsMatrix(K).inverse();
  // Local parameterisation around (R, t): R(d) = exp(d_w) R, t(d) = normalise(t + B d_t).
  auto fundamental = [&](const Eigen::Matrix3d &Rc, const Eigen::Vector3d &tc, const Eigen::Matrix<double, 5, 1> &d) {
    const Eigen::Matrix3d Rd = so3Exp<double>(Eigen::Vector3d(d.head<3>())) * Rc;
    const Eigen::Vector3d td = (tc + tangentBasis(tc) * d.tail<2>()).normalized();
    return Eigen::Matrix3d(Kinv.transpose() * so3Hat<double>(td) * Rd * Kinv);
  };
  Eigen::Matrix3d Rc = R;
  Eigen::Vector3d tc = t.normalized();
  Eigen::VectorXd r, rPlus, rMinus;
  sampsonResiduals(fundamental(Rc, tc, Eigen::Matrix<double, 5, 1>::Zero()), p1, p2, index, r);
  double lambda = kRefineInitialLambda;
  bool anyStep = false;
  double huberK = huberPx;
  Eigen::MatrixXd J(r.size(), kParams);
  for (int it = 0; it < kRefineIterations; ++it) {
    // Huber width from the residuals' robust spread (Huber's 1.345 sigma), capped by huberPx: matches are often
    // accurate to a few hundredths of a pixel, and a fixed pixel-sized width would let the worst ones steer.
    huberK = std::min(huberPx, std::max(kMinHuberPx, kHuberTuning * robustSigma(r)));
    const double cost = huberCost(r, huberK);
    for (int k = 0; k < kParams; ++k) {
      Eigen::Matrix<double, 5, 1> d = Eigen::Matrix<double, 5, 1>::Zero();
      d[k] = kRefineNumericStep;
      sampsonResiduals(fundamental(Rc, tc, d), p1, p2, index, rPlus);
      d[k] = -kRefineNumericStep;
      sampsonResiduals(fundamental(Rc, tc, d), p1, p2, index, rMinus);
      J.col(k) = (rPlus - rMinus) / (2. * kRefineNumericStep);
    }
    // Iteratively reweighted least squares for the Huber kernel.
    Eigen::VectorXd w(r.size());
    for (Eigen::Index i = 0; i < r.size(); ++i) {
      w[i] = std::abs(r[i]) <= huberK ? 1. : huberK / std::abs(r[i]);
    }
    const Eigen::Matrix<double, 5, 5> H = J.transpose() * w.asDiagonal() * J;
    const Eigen::Matrix<double, 5, 1> g = J.transpose() * w.asDiagonal() * r;
    bool improved = false;
    while (lambda < kRefineMaxLambda) {
      Eigen::Matrix<double, 5, 5> Hd = H;
      Hd.diagonal() *= 1. + lambda;
      const Eigen::Matrix<double, 5, 1> d = -Hd.ldlt().solve(g);
      Eigen::VectorXd rNew;
      sampsonResiduals(fundamental(Rc, tc, d), p1, p2, index, rNew);
      const double newCost = huberCost(rNew, huberK);
      if (newCost < cost) {
        anyStep = true;
        Rc = so3Exp<double>(Eigen::Vector3d(d.head<3>())) * Rc;
        tc = (tc + tangentBasis(tc) * d.tail<2>()).normalized();
        const bool converged = cost - newCost < kRefineMinRelativeDecrease * cost;
        r = rNew;
        lambda *= kRefineLambdaDown;
        improved = !converged;
        break;
      }
      lambda *= kRefineLambdaUp;
    }
    if (!improved) {
      break;
    }
  }
  if (translationDirSigmaDeg) {
    *translationDirSigmaDeg = translationDirectionSigmaDeg(fundamental, Rc, tc, p1, p2, index, huberK);
  }
  if (!anyStep) {
    return false;
  }
  R = Rc;
  t = tc;
  return true;
}
} // namespace hslam
