/*
 * H-SLAM for ViSP.
 */
#include "loop/GlobalBundleAdjustment.h"
#include "loop/LoopSolverOptions.h"

#include <visp3/hslam/vpHSlamException.h>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

namespace hslam
{
namespace
{
//! Below this depth (in units of the point's own scale) an observation is behind or on the camera: refused.
constexpr double kMinDepth = 1e-6;
//! Inverse depths stay positive (a point cannot cross to behind its host).
constexpr double kMinIdepth = 1e-8;

//! Where the point hosted in h (pixel ray, inverse depth) lands in o, rho-scaled (see the file comment).
template <typename T>
void pointInObserver(const T *host, const T *observer, const T *idepth, const Eigen::Vector3d &ray, T *out)
{
  // cMw stored as (qx, qy, qz, qw, t): Ceres' rotation helpers take (w, x, y, z).
  const T qhInverse[4] = {host[3], -host[0], -host[1], -host[2]};
  const T qo[4] = {observer[3], observer[0], observer[1], observer[2]};
  // rho X_w = R_h^T (ray - rho t_h)
  const T a[3] = {T(ray.x()) - idepth[0] * host[4], T(ray.y()) - idepth[0] * host[5], T(ray.z()) - idepth[0] * host[6]};
  T w[3];
  ceres::UnitQuaternionRotatePoint(qhInverse, a, w);
  // rho X_o = R_o (rho X_w) + rho t_o
  ceres::UnitQuaternionRotatePoint(qo, w, out);
  out[0] += idepth[0] * observer[4];
  out[1] += idepth[0] * observer[5];
  out[2] += idepth[0] * observer[6];
}

struct ReprojectionError {
  ReprojectionError(const PinholeIntrinsics &K, const Eigen::Vector3d &ray, double u, double v)
      : K(K), ray(ray), u(u), v(v)
  {
  }
  template <typename T> bool operator()(const T *host, const T *observer, const T *idepth, T *residual) const
  {
    T X[3];
    pointInObserver(host, observer, idepth, ray, X);
    if (!(X[2] > T(kMinDepth) * idepth[0])) {
      return false; // behind the observer: not a step Ceres may take
    }
    residual[0] = T(K.fx) * X[0] / X[2] + T(K.cx) - T(u);
    residual[1] = T(K.fy) * X[1] / X[2] + T(K.cy) - T(v);
    return true;
  }
  PinholeIntrinsics K;
  Eigen::Vector3d ray;
  double u, v;
};
//! Stops the solver when the caller asks (GlobalBundleOptions::cancel).
class CancelCallback : public ceres::IterationCallback
{
public:
  explicit CancelCallback(const std::atomic<bool> &cancel) : m_cancel(cancel) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary &) override
  {
    return m_cancel.load() ? ceres::SOLVER_ABORT : ceres::SOLVER_CONTINUE;
  }

private:
  const std::atomic<bool> &m_cancel;
};
} // namespace

void GlobalBundleAdjustment::addKeyframe(int id, const SE3d &cMw, bool fixed)
{
  Pose p;
  const Eigen::Quaterniond &q = cMw.unitQuaternion();
  p.x = {q.x(), q.y(), q.z(), q.w(), cMw.translation().x(), cMw.translation().y(), cMw.translation().z()};
  p.fixed = fixed;
  m_keyframes[id] = p;
}

int GlobalBundleAdjustment::addPoint(const BundlePoint &point)
{
  auto host = m_keyframes.find(point.hostId);
  if (host == m_keyframes.end() || !(point.idepth > 0.) || !std::isfinite(point.idepth)) {
    return -1;
  }
  Point p;
  p.host = point.hostId;
  p.u = point.u;
  p.v = point.v;
  p.idepth = point.idepth;
  const Eigen::Vector3d ray = m_K.unproject(p.u, p.v, 1.);
  for (const BundlePoint::Observation &o : point.observations) {
    auto observer = m_keyframes.find(o.keyframeId);
    if (observer == m_keyframes.end() || o.keyframeId == point.hostId || !std::isfinite(o.u) || !std::isfinite(o.v)) {
      continue;
    }
    double X[3];
    pointInObserver(host->second.x.data(), observer->second.x.data(), &p.idepth, ray, X);
    if (X[2] > kMinDepth * p.idepth) {
      p.observations.push_back(o);
    }
  }
  if (p.observations.empty()) {
    return -1;
  }
  m_points.push_back(std::move(p));
  return static_cast<int>(m_points.size()) - 1;
}

SE3d GlobalBundleAdjustment::keyframe(int id) const
{
  auto it = m_keyframes.find(id);
  if (it == m_keyframes.end()) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "GlobalBundleAdjustment: unknown keyframe " + std::to_string(id));
  }
  const std::array<double, 7> &x = it->second.x;
  return SE3d(Eigen::Quaterniond(x[3], x[0], x[1], x[2]), Eigen::Vector3d(x[4], x[5], x[6]));
}

double GlobalBundleAdjustment::rmsReprojection(int &count) const
{
  double sum = 0.;
  count = 0;
  for (const Point &p : m_points) {
    const Eigen::Vector3d ray = m_K.unproject(p.u, p.v, 1.);
    for (const BundlePoint::Observation &o : p.observations) {
      const ReprojectionError error(m_K, ray, o.u, o.v);
      double r[2];
      if (error(m_keyframes.at(p.host).x.data(), m_keyframes.at(o.keyframeId).x.data(), &p.idepth, r)) {
        sum += r[0] * r[0] + r[1] * r[1];
        ++count;
      }
    }
  }
  return count > 0 ? std::sqrt(sum / count) : 0.;
}

void GlobalBundleAdjustment::holdGauge()
{
  int fixed = 0;
  for (const auto &k : m_keyframes) {
    fixed += k.second.fixed ? 1 : 0;
  }
  for (auto it = m_keyframes.begin(); it != m_keyframes.end() && fixed < 2; ++it) {
    if (!it->second.fixed) {
      it->second.fixed = true;
      ++fixed;
    }
  }
}

std::map<int, double *> GlobalBundleAdjustment::poseBlocks(std::vector<std::array<double, 7>> &poses) const
{
  std::map<int, double *> block;
  poses.reserve(m_keyframes.size());
  for (const auto &k : m_keyframes) {
    poses.push_back(k.second.x);
  }
  size_t next = 0;
  for (const auto &k : m_keyframes) {
    block[k.first] = poses[next++].data();
  }
  return block;
}

void GlobalBundleAdjustment::addPointResiduals(ceres::Problem &problem, ceres::LossFunction *loss,
                                               const std::map<int, double *> &block)
{
  for (Point &p : m_points) {
    const Eigen::Vector3d ray = m_K.unproject(p.u, p.v, 1.);
    for (const BundlePoint::Observation &o : p.observations) {
      problem.AddResidualBlock(
          new ceres::AutoDiffCostFunction<ReprojectionError, 2, 7, 7, 1>(new ReprojectionError(m_K, ray, o.u, o.v)),
          loss, block.at(p.host), block.at(o.keyframeId), &p.idepth);
    }
    problem.SetParameterLowerBound(&p.idepth, 0, kMinIdepth);
  }
}

std::vector<double *> GlobalBundleAdjustment::setPoseBlocks(ceres::Problem &problem, ceres::Manifold *manifold,
                                                            const std::map<int, double *> &block) const
{
  std::vector<double *> used;
  for (const auto &k : m_keyframes) {
    double *x = block.at(k.first);
    if (!problem.HasParameterBlock(x)) {
      continue;
    }
    problem.SetManifold(x, manifold);
    if (k.second.fixed) {
      problem.SetParameterBlockConstant(x);
    }
    used.push_back(x);
  }
  return used;
}

bool GlobalBundleAdjustment::keepOrRestore(bool solverUsable, const std::vector<std::array<double, 7>> &poses,
                                           const std::map<int, double *> &block,
                                           const std::vector<double> &idepthBackup)
{
  bool usable = solverUsable;
  for (const std::array<double, 7> &x : poses) {
    for (double v : x) {
      usable = usable && std::isfinite(v);
    }
  }
  for (const Point &p : m_points) {
    usable = usable && std::isfinite(p.idepth) && p.idepth > 0.;
  }
  if (usable) {
    for (auto &k : m_keyframes) {
      const double *x = block.at(k.first);
      std::copy(x, x + 7, k.second.x.begin());
    }
  } else { // nothing changes
    for (size_t i = 0; i < m_points.size(); ++i) {
      m_points[i].idepth = idepthBackup[i];
    }
  }
  return usable;
}

GlobalBundleSummary GlobalBundleAdjustment::optimize(const GlobalBundleOptions &options)
{
  const auto t0 = std::chrono::steady_clock::now();
  GlobalBundleSummary out;
  out.keyframes = static_cast<int>(m_keyframes.size());
  out.points = static_cast<int>(m_points.size());
  out.rmsBeforePx = rmsReprojection(out.observations);
  if (m_points.empty()) {
    out.usable = true;
    return out;
  }
  // Gauge: at least two held keyframes (see the file comment).
  holdGauge();

  ceres::Problem::Options problemOptions;
  problemOptions.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problemOptions.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problemOptions);
  ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>> poseManifold;
  ceres::HuberLoss loss(options.huberPx);
  // The poses are solved in one contiguous buffer in keyframe-id order (the points already are, in m_points): Ceres
  // orders the blocks of an elimination group by address, and map nodes' addresses depend on what the heap held
  // before, so the same problem summed in another order ended 1e-6 apart and diverged later (a slam run's output
  // changed with the dataset program's progress line).
  std::vector<std::array<double, 7>> poses;
  const std::map<int, double *> block = poseBlocks(poses);
  addPointResiduals(problem, &loss, block);
  auto *ordering = new ceres::ParameterBlockOrdering; // owned by the solver options
  for (Point &p : m_points) {
    ordering->AddElementToGroup(&p.idepth, 0);
  }
  for (double *x : setPoseBlocks(problem, &poseManifold, block)) {
    ordering->AddElementToGroup(x, 1);
  }
  ceres::Solver::Options solverOptions = loopSolverOptions(options.maxIterations, ceres::SPARSE_SCHUR);
  solverOptions.linear_solver_ordering.reset(ordering);
  solverOptions.num_threads = std::max(1, options.threads);
  std::unique_ptr<CancelCallback> callback;
  if (options.cancel) {
    callback = std::make_unique<CancelCallback>(*options.cancel);
    solverOptions.callbacks.push_back(callback.get());
  }
  std::vector<double> idepthBackup;
  for (const Point &p : m_points) {
    idepthBackup.push_back(p.idepth);
  }
  ceres::Solver::Summary summary;
  ceres::Solve(solverOptions, &problem, &summary);
  out.usable = keepOrRestore(summary.IsSolutionUsable() && summary.termination_type != ceres::USER_FAILURE &&
                                 !(options.cancel && options.cancel->load()),
                             poses, block, idepthBackup);
  out.iterations = static_cast<int>(summary.iterations.size());
  int after = 0;
  out.rmsAfterPx = rmsReprojection(after);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}
} // namespace hslam
