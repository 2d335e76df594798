/*
 * H-SLAM for ViSP.
 */
// WindowOptimizer, the normal equations of one Levenberg-Marquardt step: the frame system assembled from the
// accumulated pair blocks (relative to absolute parametrisation), the marginalisation prior and the pose priors,
// the gauge and scale directions, the damped solve and the step applied to states and points. The iteration loop,
// outliers and write-back are in WindowOptimizer.cpp.
#include "mapping/WindowOptimizer.h"

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! Affine offsets b are in intensity units: divided by the 8-bit range they compare with the other step parts.
constexpr double kAffineOffsetStepScale = 1. / 255.;
//! A squared scale-direction norm below this (window without baseline) means there is no scale to fix.
constexpr double kMinScaleDirectionSqNorm = 1e-18;
} // namespace

void WindowOptimizer::assembleFullSystem(const WindowAccumulator &acc, Eigen::MatrixXd &H, Eigen::VectorXd &b) const
{
  const int n = static_cast<int>(m_frames.size());
  H.setZero(n * kFrameDims, n * kFrameDims);
  b.setZero(n * kFrameDims);
  for (int f = 0; f < n; ++f) {
    H.block<kFrameDims, kFrameDims>(f * kFrameDims, f * kFrameDims) += acc.frameH[static_cast<size_t>(f)];
    b.segment<kFrameDims>(f * kFrameDims) += acc.frameB[static_cast<size_t>(f)];
  }
  for (int h = 0; h < n; ++h) {
    for (int t = 0; t < n; ++t) {
      if (h == t) {
        continue;
      }
      const size_t k = static_cast<size_t>(h * kMaxWindowKeyframes + t);
      const Mat8d &Hp = acc.pairH[k];
      if (Hp.diagonal().sum() == 0.) {
        continue;
      }
      const FramePairPrecalc &pair = m_ctx.pair(h, t);
      const Mat8d &Ah = pair.dRelative_dHost;
      const Mat8d &At = pair.dRelative_dTarget;
      const Mat8d HAh = Hp * Ah;
      const Mat8d HAt = Hp * At;
      H.block<kFrameDims, kFrameDims>(h * kFrameDims, h * kFrameDims).noalias() += Ah.transpose() * HAh;
      H.block<kFrameDims, kFrameDims>(t * kFrameDims, t * kFrameDims).noalias() += At.transpose() * HAt;
      const Mat8d Hht = Ah.transpose() * HAt;
      H.block<kFrameDims, kFrameDims>(h * kFrameDims, t * kFrameDims) += Hht;
      H.block<kFrameDims, kFrameDims>(t * kFrameDims, h * kFrameDims) += Hht.transpose();
      b.segment<kFrameDims>(h * kFrameDims).noalias() += Ah.transpose() * acc.pairB[k];
      b.segment<kFrameDims>(t * kFrameDims).noalias() += At.transpose() * acc.pairB[k];
    }
  }
}

double WindowOptimizer::priorEnergy() const
{
  // DSO: affine priors pull a and b towards 0 (weights from the tracker parameters).
  double e = 0.;
  for (const KeyframeState &s : m_states) {
    e += m_affinePriorA * s.a * s.a + m_affinePriorB * s.b * s.b;
  }
  return e + m_prior.energy(m_states);
}

int WindowOptimizer::gaugeFixedIndex() const
{
  for (size_t i = 0; i < m_frames.size(); ++i) {
    if (m_frames[i].kf->id() == m_gaugeKeyframeId) {
      return static_cast<int>(i);
    }
  }
  // The gauge keyframe left: the prior holds the gauge, unless it holds nothing (then fix the oldest).
  return m_prior.hasInformation() || m_frames.empty() ? -1 : 0;
}

Eigen::VectorXd WindowOptimizer::scaleDirection() const
{
  // Scaling the scene about the anchor camera's centre: c_iMa = (R, t) -> (R, s t), i.e. a left translation
  // perturbation t_ia ds of every pose (inverse depths scale by 1/s, eliminated by the Schur complement).
  const int fixed = gaugeFixedIndex();
  const SE3d aMw = fixed >= 0 ? m_states[static_cast<size_t>(fixed)].cMw : m_gaugeAnchor.cMw;
  const SE3d wMa = aMw.inverse();
  Eigen::VectorXd n = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(m_frames.size()) * kFrameDims);
  for (size_t i = 0; i < m_frames.size(); ++i) {
    n.segment<3>(static_cast<Eigen::Index>(i) * kFrameDims) = (m_states[i].cMw * wMa).translation();
  }
  return n;
}

void WindowOptimizer::addPriors(Eigen::MatrixXd &H, Eigen::VectorXd &b) const
{
  // DSO: affine priors towards a = b = 0, then the marginalisation prior's quadratic.
  for (size_t i = 0; i < m_frames.size(); ++i) {
    const int o = static_cast<int>(i) * kFrameDims;
    H(o + 6, o + 6) += m_affinePriorA;
    H(o + 7, o + 7) += m_affinePriorB;
    b[o + 6] += m_affinePriorA * m_states[i].a;
    b[o + 7] += m_affinePriorB * m_states[i].b;
  }
  if (m_prior.hasInformation()) {
    H += m_prior.H();
    b += m_prior.gradient(m_states);
  }
}

void WindowOptimizer::reducedSystem(Eigen::MatrixXd &H, Eigen::VectorXd &b, bool withPriors)
{
  syncStatesAndPoints();
  prepareContext();
  WindowAccumulator acc;
  linearizeAll(m_allPoints, acc);
  schurAll(m_allPoints, 0., acc);
  assembleFullSystem(acc, H, b);
  H -= acc.Hsc;
  b -= acc.bsc;
  if (withPriors) {
    addPriors(H, b);
  }
}

double WindowOptimizer::totalEnergy()
{
  syncStatesAndPoints();
  prepareContext();
  return energyAll(m_allPoints) + priorEnergy();
}

bool WindowOptimizer::solveStep(double lambda, Eigen::VectorXd &dx)
{
  const int n = static_cast<int>(m_frames.size());
  const int dim = n * kFrameDims;
  m_acc.Hsc.setZero();
  m_acc.bsc.setZero();
  schurAll(m_allPoints, lambda, m_acc);
  m_Hred = m_H;
  m_Hred.diagonal() *= (1. + lambda);
  m_Hred -= m_acc.Hsc;
  m_bred = m_b - m_acc.bsc;

  // Free dimensions: everything but the gauge keyframe and states without any information.
  const int fixed = gaugeFixedIndex();
  std::vector<int> freeDims;
  freeDims.reserve(static_cast<size_t>(dim));
  for (int i = 0; i < dim; ++i) {
    if (i / kFrameDims != fixed && m_H(i, i) > 0.) {
      freeDims.push_back(i);
    }
  }
  dx.setZero(dim);
  const int m = static_cast<int>(freeDims.size());
  if (m == 0) {
    return true;
  }
  // Jacobi scaling (the solution does not depend on it; the conditioning does).
  Eigen::VectorXd s(m), bs(m);
  Eigen::MatrixXd Hs(m, m);
  for (int i = 0; i < m; ++i) {
    s[i] = 1. / std::sqrt(m_H(freeDims[static_cast<size_t>(i)], freeDims[static_cast<size_t>(i)]));
  }
  for (int i = 0; i < m; ++i) {
    for (int j = 0; j < m; ++j) {
      Hs(i, j) = s[i] * s[j] * m_Hred(freeDims[static_cast<size_t>(i)], freeDims[static_cast<size_t>(j)]);
    }
    bs[i] = s[i] * m_bred[freeDims[static_cast<size_t>(i)]];
  }
  // Scale gauge: constrain the step orthogonal to the scale direction (ns = S^-1 n in scaled coordinates).
  const Eigen::VectorXd nFull = scaleDirection();
  Eigen::VectorXd ns(m);
  for (int i = 0; i < m; ++i) {
    ns[i] = nFull[freeDims[static_cast<size_t>(i)]] / s[i];
  }
  // Enough anchored points (re-used global points tied to stored keyframes) measure the scale: no gauge then.
  const double nsSq = m_anchoredPoints >= m_anchorMinForScale ? 0. : ns.squaredNorm();
  if (nsSq > kMinScaleDirectionSqNorm) {
    Hs.noalias() += ns * ns.transpose() / nsSq;
  }
  m_ldlt.compute(Hs);
  if (m_ldlt.info() != Eigen::Success) {
    return false;
  }
  Eigen::VectorXd xs = -m_ldlt.solve(bs);
  if (!xs.allFinite()) {
    return false;
  }
  if (nsSq > kMinScaleDirectionSqNorm) {
    xs -= ns * (ns.dot(xs) / nsSq);
  }
  for (int i = 0; i < m; ++i) {
    dx[freeDims[static_cast<size_t>(i)]] = s[i] * xs[i];
  }
  return true;
}

void WindowOptimizer::backupStates()
{
  for (size_t i = 0; i < m_frames.size(); ++i) {
    m_frames[i].backup = m_states[i];
  }
  for (WindowPoint &p : m_points) {
    p.idepthBackup = p.obs.idepth;
  }
}

void WindowOptimizer::restoreStates()
{
  for (size_t i = 0; i < m_frames.size(); ++i) {
    m_states[i] = m_frames[i].backup;
  }
  for (WindowPoint &p : m_points) {
    p.obs.idepth = p.idepthBackup;
  }
}

void WindowOptimizer::applyStep(const Eigen::VectorXd &dx, double lambda)
{
  const int n = static_cast<int>(m_frames.size());
  for (int i = 0; i < n; ++i) {
    const Vec8d d = dx.segment<kFrameDims>(i * kFrameDims);
    KeyframeState &s = m_states[static_cast<size_t>(i)];
    s.cMw = SE3d::exp(d.head<6>()) * s.cMw;
    s.a += d[6];
    s.b += d[7];
  }
  // Back-substitution: d_rho = -(b_rho + H_rho,x dx) / (H_rho,rho (1 + lambda)), the same damping as the Schur.
  for (size_t pi = 0; pi < m_points.size(); ++pi) {
    WindowPoint &p = m_points[pi];
    const double H = p.Hpp * (1. + lambda);
    if (p.inlierResiduals == 0 || !(H > 0.)) {
      continue;
    }
    const Vec8d *cross = m_hxp.data() + pi * kMaxWindowKeyframes;
    double rhs = p.bp;
    for (int f = 0; f < n; ++f) {
      rhs += cross[f].dot(dx.segment<kFrameDims>(f * kFrameDims));
    }
    p.obs.idepth -= rhs / H;
  }
}

double WindowOptimizer::stepNorm(const Eigen::VectorXd &dx) const
{
  // Translation is compared in units of the scene depth (DSO normalises it by the mean inverse depth).
  double meanIdepth = 0.;
  for (const WindowPoint &p : m_points) {
    meanIdepth += p.obs.idepth;
  }
  meanIdepth = m_points.empty() ? 1. : std::fabs(meanIdepth) / static_cast<double>(m_points.size());
  double norm = 0.;
  for (int i = 0; i < static_cast<int>(m_frames.size()); ++i) {
    const Vec8d d = dx.segment<kFrameDims>(i * kFrameDims);
    norm = std::max({norm, d.head<3>().norm() * meanIdepth, d.segment<3>(3).norm(), std::fabs(d[6]),
                     std::fabs(d[7]) * kAffineOffsetStepScale});
  }
  return norm;
}
} // namespace hslam
