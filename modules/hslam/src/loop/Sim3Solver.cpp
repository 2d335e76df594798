/*
 * H-SLAM for ViSP.
 */
#include "loop/Sim3Solver.h"

#include "loop/LoopSolverOptions.h"
#include "loop/Sim3Parameters.h"

#include <visp3/hslam/vpHSlamException.h>

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>

namespace hslam
{
namespace
{
//! Points closer than this to the camera plane are not projected (depth in the units of the map).
constexpr double kMinDepth = 1e-9;
//! Refinement: Levenberg-Marquardt iterations at most.
constexpr int kRefineIterations = 20;

template <typename T> bool project(const PinholeIntrinsics &K, const Eigen::Matrix<T, 3, 1> &X, T &u, T &v)
{
  if (!(X.z() > T(kMinDepth))) {
    return false;
  }
  u = T(K.fx) * X.x() / X.z() + T(K.cx);
  v = T(K.fy) * X.y() / X.z() + T(K.cy);
  return true;
}

//! Squared reprojection errors of one match under S21 in image 2 and image 1 (infinity when behind a camera).
void reprojectionErrors(const Sim3Correspondence &m, const Sim3d &S21, const Sim3d &S12, const PinholeIntrinsics &K1,
                        const PinholeIntrinsics &K2, double &e2, double &e1)
{
  double u, v;
  e2 = e1 = std::numeric_limits<double>::infinity();
  if (project(K2, Eigen::Vector3d(S21 * m.X1), u, v)) {
    e2 = (Eigen::Vector2d(u, v) - m.uv2).squaredNorm();
  }
  if (project(K1, Eigen::Vector3d(S12 * m.X2), u, v)) {
    e1 = (Eigen::Vector2d(u, v) - m.uv1).squaredNorm();
  }
}

int countInliers(const std::vector<Sim3Correspondence> &matches, const Sim3d &S21, const PinholeIntrinsics &K1,
                 const PinholeIntrinsics &K2, double maxSq, std::vector<bool> &inliers)
{
  const Sim3d S12 = S21.inverse();
  inliers.assign(matches.size(), false);
  int n = 0;
  for (size_t i = 0; i < matches.size(); ++i) {
    double e2, e1;
    reprojectionErrors(matches[i], S21, S12, K1, K2, e2, e1);
    inliers[i] = e2 < maxSq && e1 < maxSq;
    n += inliers[i] ? 1 : 0;
  }
  return n;
}

struct TwoWayReprojection {
  TwoWayReprojection(const Sim3Correspondence &m, const PinholeIntrinsics &K1, const PinholeIntrinsics &K2)
      : m(m), K1(K1), K2(K2)
  {
  }
  template <typename T> bool operator()(const T *x, T *r) const
  {
    if (!sim3ParametersValid(x)) {
      return false;
    }
    const Sim3<T> S21 = sim3FromParameters(x);
    T u2, v2, u1, v1;
    if (!project(K2, Eigen::Matrix<T, 3, 1>(S21 * Eigen::Matrix<T, 3, 1>(m.X1.cast<T>())), u2, v2) ||
        !project(K1, Eigen::Matrix<T, 3, 1>(S21.inverse() * Eigen::Matrix<T, 3, 1>(m.X2.cast<T>())), u1, v1)) {
      return false;
    }
    r[0] = u2 - T(m.uv2.x());
    r[1] = v2 - T(m.uv2.y());
    r[2] = u1 - T(m.uv1.x());
    r[3] = v1 - T(m.uv1.y());
    return true;
  }
  Sim3Correspondence m;
  PinholeIntrinsics K1, K2;
};
} // namespace

Sim3d hornSim3(const std::vector<Eigen::Vector3d> &X1, const std::vector<Eigen::Vector3d> &X2)
{
  if (X1.size() != X2.size() || X1.size() < 3) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "hornSim3: needs at least 3 pairs of points (got " +
                                                                  std::to_string(X1.size()) + " and " +
                                                                  std::to_string(X2.size()) + ")");
  }
  const double n = static_cast<double>(X1.size());
  Eigen::Vector3d c1 = Eigen::Vector3d::Zero(), c2 = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < X1.size(); ++i) {
    c1 += X1[i];
    c2 += X2[i];
  }
  c1 /= n;
  c2 /= n;
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero(); // sum of (X1 - c1)(X2 - c2)^T: M(a, b) = S_ab of Horn's paper
  double spread1 = 0.;
  for (size_t i = 0; i < X1.size(); ++i) {
    const Eigen::Vector3d a = X1[i] - c1, b = X2[i] - c2;
    M += a * b.transpose();
    spread1 += a.squaredNorm();
  }
  if (!(spread1 > 0.)) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "hornSim3: the first points all coincide");
  }
  // Horn's N (eq. of section 4): its eigenvector of the largest eigenvalue is the unit quaternion (w, x, y, z).
  const double Sxx = M(0, 0), Sxy = M(0, 1), Sxz = M(0, 2), Syx = M(1, 0), Syy = M(1, 1), Syz = M(1, 2), Szx = M(2, 0),
               Szy = M(2, 1), Szz = M(2, 2);
  Eigen::Matrix4d N;
  N << Sxx + Syy + Szz, Syz - Szy, Szx - Sxz, Sxy - Syx, //
      Syz - Szy, Sxx - Syy - Szz, Sxy + Syx, Szx + Sxz,  //
      Szx - Sxz, Sxy + Syx, -Sxx + Syy - Szz, Syz + Szy, //
      Sxy - Syx, Szx + Sxz, Syz + Szy, -Sxx - Syy + Szz;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(N);
  const Eigen::Vector4d e = eig.eigenvectors().col(3); // eigenvalues ascending
  const Eigen::Quaterniond q(e[0], e[1], e[2], e[3]);
  const Eigen::Matrix3d R = q.normalized().toRotationMatrix();
  double dot = 0.;
  for (size_t i = 0; i < X1.size(); ++i) {
    dot += (X2[i] - c2).dot(R * (X1[i] - c1));
  }
  const double s = dot / spread1;
  if (!(s > 0.)) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "hornSim3: degenerate configuration (scale <= 0)");
  }
  return Sim3d(q, c2 - s * (R * c1), s);
}

bool refineSim3(const std::vector<Sim3Correspondence> &matches, const PinholeIntrinsics &K1,
                const PinholeIntrinsics &K2, double huberPx, Sim3d &S21)
{
  if (matches.empty()) {
    return false;
  }
  std::array<double, kSim3ParameterSize> x = sim3Parameters(S21);
  if (!sim3ParametersValid(x.data())) {
    return false; // a scale beyond e^+-20 (Horn on a degenerate sample): Ceres would abort on it
  }
  ceres::Problem problem;
  for (const Sim3Correspondence &m : matches) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<TwoWayReprojection, 4, kSim3ParameterSize>(new TwoWayReprojection(m, K1, K2)),
        new ceres::HuberLoss(huberPx), x.data());
  }
  problem.SetManifold(x.data(), newSim3Manifold());
  const ceres::Solver::Options options = loopSolverOptions(kRefineIterations, ceres::DENSE_QR);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  if (!summary.IsSolutionUsable() || !sim3ParametersValid(x.data())) {
    return false;
  }
  S21 = sim3FromParameters(x.data());
  return true;
}

namespace
{
//! RANSAC over minimal samples of three matches (hornSim3), adaptive stopping: the best hypothesis into \e best.
void sampleHypotheses(const std::vector<Sim3Correspondence> &matches, const PinholeIntrinsics &K1,
                      const PinholeIntrinsics &K2, const Sim3RansacOptions &options, double maxSq, Sim3Estimate &best)
{
  const int n = static_cast<int>(matches.size());
  std::mt19937 rng(options.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  int required = options.maxIterations;
  std::vector<bool> inliers;
  std::vector<Eigen::Vector3d> a(3), b(3);
  for (int it = 0; it < required && it < options.maxIterations; ++it) {
    ++best.iterations;
    int idx[3];
    idx[0] = pick(rng);
    do {
      idx[1] = pick(rng);
    } while (idx[1] == idx[0]);
    do {
      idx[2] = pick(rng);
    } while (idx[2] == idx[0] || idx[2] == idx[1]);
    for (int k = 0; k < 3; ++k) {
      a[static_cast<size_t>(k)] = matches[static_cast<size_t>(idx[k])].X1;
      b[static_cast<size_t>(k)] = matches[static_cast<size_t>(idx[k])].X2;
    }
    Sim3d S;
    try {
      S = hornSim3(a, b);
    } catch (const vpHSlamException &) {
      continue; // collinear or coincident sample
    }
    const int count = countInliers(matches, S, K1, K2, maxSq, inliers);
    if (count > best.inlierCount) {
      best.inlierCount = count;
      best.inliers = inliers;
      best.S21 = S;
      // Standard adaptive stopping: (1 - w^3)^k <= 1 - confidence with w the inlier share.
      const double w = static_cast<double>(count) / n;
      const double noOutlierSample = std::pow(w, 3.);
      if (noOutlierSample > 1. - 1e-12) {
        required = 0;
      } else if (noOutlierSample > 0.) {
        required = static_cast<int>(std::ceil(std::log(1. - options.confidence) / std::log(1. - noOutlierSample)));
      }
    }
  }
}

//! All inliers of \e best: closed form, then the non-linear refinement, each kept only if it does not lose inliers.
void polishOnInliers(const std::vector<Sim3Correspondence> &matches, const PinholeIntrinsics &K1,
                     const PinholeIntrinsics &K2, const Sim3RansacOptions &options, double maxSq, Sim3Estimate &best)
{
  std::vector<Eigen::Vector3d> A, B;
  std::vector<Sim3Correspondence> in;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (best.inliers[i]) {
      A.push_back(matches[i].X1);
      B.push_back(matches[i].X2);
      in.push_back(matches[i]);
    }
  }
  std::vector<bool> inliers;
  try {
    const Sim3d S = hornSim3(A, B);
    const int count = countInliers(matches, S, K1, K2, maxSq, inliers);
    if (count >= best.inlierCount) {
      best.S21 = S;
      best.inlierCount = count;
      best.inliers = inliers;
    }
  } catch (const vpHSlamException &) {
  }
  if (options.refine) {
    Sim3d S = best.S21;
    if (refineSim3(in, K1, K2, options.maxReprojectionPx, S)) {
      const int count = countInliers(matches, S, K1, K2, maxSq, inliers);
      if (count >= best.inlierCount) {
        best.S21 = S;
        best.inlierCount = count;
        best.inliers = inliers;
      }
    }
  }
}

//! RMS of the two-way reprojection errors of the inliers of \e estimate, pixels.
double rmsInlierReprojection(const std::vector<Sim3Correspondence> &matches, const Sim3Estimate &estimate,
                             const PinholeIntrinsics &K1, const PinholeIntrinsics &K2)
{
  const Sim3d S12 = estimate.S21.inverse();
  double sum = 0.;
  for (size_t i = 0; i < matches.size(); ++i) {
    if (estimate.inliers[i]) {
      double e2, e1;
      reprojectionErrors(matches[i], estimate.S21, S12, K1, K2, e2, e1);
      sum += e1 + e2;
    }
  }
  return estimate.inlierCount > 0 ? std::sqrt(sum / (2. * estimate.inlierCount)) : 0.;
}
} // namespace

Sim3Estimate estimateSim3Ransac(const std::vector<Sim3Correspondence> &matches, const PinholeIntrinsics &K1,
                                const PinholeIntrinsics &K2, const Sim3RansacOptions &options)
{
  Sim3Estimate best;
  best.inliers.assign(matches.size(), false);
  const int n = static_cast<int>(matches.size());
  if (n < std::max(3, options.minInliers)) {
    return best;
  }
  const double maxSq = options.maxReprojectionPx * options.maxReprojectionPx;
  sampleHypotheses(matches, K1, K2, options, maxSq, best);
  if (best.inlierCount < std::max(3, options.minInliers)) {
    best.success = false;
    return best;
  }
  polishOnInliers(matches, K1, K2, options, maxSq, best);
  best.rmsReprojectionPx = rmsInlierReprojection(matches, best, K1, K2);
  best.success = best.inlierCount >= options.minInliers;
  return best;
}
} // namespace hslam
