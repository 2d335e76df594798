/*
 * H-SLAM for ViSP.
 */
/*
  WindowOptimizer, second half: keyframe marginalisation (DSO EnergyFunctional::marginalizePointsF and
  marginalizeFrame, FullSystem::flagFramesForMarginalization) and the single-point inverse-depth optimisation used
  by point activation (DSO FullSystem::optimizeImmaturePoint).
*/
#include "mapping/WindowOptimizer.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cmath>
#include <limits>
#include <string>

namespace hslam
{
namespace
{
//! DSO flagFramesForMarginalization: distance score 1 / (eps + d) keeps coincident keyframes finite.
constexpr double kDistanceScoreEpsilon = 1e-5;
//! DSO: the newest keyframe before the new one is never chosen by the distance score (setting_minFrameAge = 1),
//! nor is the new one: the two newest are protected.
constexpr int kProtectedNewestKeyframes = 2;
//! DSO optimizeImmaturePoint: LM on one inverse depth, start damping 0.1, x0.5 after success, x5 after failure.
constexpr double kPointInitialLambda = 0.1;
constexpr double kPointLambdaAccept = 0.5;
constexpr double kPointLambdaReject = 5.;
//! Stop refining a new point when the inverse-depth step falls below this fraction of the inverse depth.
constexpr double kPointRelativeStepConverged = 1e-4;
//! A new point needs at least this many inlier residuals to be accepted.
constexpr int kMinInlierResidualsActivate = 1;

std::string where(int line)
{
  return std::string(__FILE__) + ":" + std::to_string(line) + ": ";
}
} // namespace

void WindowOptimizer::remapAfterFrameRemoval(int removed)
{
  for (WindowPoint &p : m_points) {
    if (p.host > removed) {
      --p.host;
    }
    for (WindowResidual &r : p.residuals) {
      if (r.target > removed) {
        --r.target;
      }
    }
  }
}

std::vector<PairInformation> WindowOptimizer::pairInformation(int keyframeId)
{
  std::vector<PairInformation> out;
  int idx = -1;
  for (size_t i = 0; i < m_frames.size(); ++i) {
    if (m_frames[i].kf->id() == keyframeId) {
      idx = static_cast<int>(i);
    }
  }
  if (idx < 0) {
    return out;
  }
  const int n = static_cast<int>(m_frames.size());
  WindowAccumulator fresh;
  if (!m_accCurrent) {
    syncStatesAndPoints();
    prepareContext();
    fresh.reset(n);
    linearizeRange(m_ctx, m_points, m_allPoints, 0, m_allPoints.size(), m_hxp.data(), fresh);
  }
  const WindowAccumulator &acc = m_accCurrent ? m_acc : fresh;
  std::vector<int> count(static_cast<size_t>(n), 0);
  for (const WindowPoint &p : m_points) {
    for (const WindowResidual &r : p.residuals) {
      if (r.state != ResidualState::inlier) {
        continue;
      }
      if (p.host == idx) {
        ++count[static_cast<size_t>(r.target)];
      } else if (r.target == idx) {
        ++count[static_cast<size_t>(p.host)];
      }
    }
  }
  const SE3d &thisMw = m_states[static_cast<size_t>(idx)].cMw;
  for (int j = 0; j < n; ++j) {
    if (j == idx || count[static_cast<size_t>(j)] == 0) {
      continue;
    }
    PairInformation info;
    info.otherKeyframeId = m_frames[static_cast<size_t>(j)].kf->id();
    info.otherMthis = m_states[static_cast<size_t>(j)].cMw * thisMw.inverse();
    info.residuals = count[static_cast<size_t>(j)];
    // Residuals hosted here: relative pose otherMthis itself. Hosted in the other: thisMother = otherMthis^-1,
    // whose left perturbation is -Ad(otherMthis^-1) times that of otherMthis.
    const Mat8d &Hforward = acc.pairH[static_cast<size_t>(idx * kMaxWindowKeyframes + j)];
    const Mat8d &Hbackward = acc.pairH[static_cast<size_t>(j * kMaxWindowKeyframes + idx)];
    const Eigen::Matrix<double, 6, 6> Ad = info.otherMthis.inverse().adjoint();
    info.information = Hforward.topLeftCorner<6, 6>() + Ad.transpose() * Hbackward.topLeftCorner<6, 6>() * Ad;
    info.information = 0.5 * (info.information + info.information.transpose());
    out.push_back(info);
  }
  return out;
}

void WindowOptimizer::marginalizeHostedPoints(int idx)
{
  const int n = static_cast<int>(m_frames.size());
  std::vector<int> hosted;
  for (size_t i = 0; i < m_points.size(); ++i) {
    if (m_points[i].host == idx) {
      hosted.push_back(static_cast<int>(i));
    }
  }
  WindowAccumulator acc;
  acc.reset(n);
  linearizeRange(m_ctx, m_points, hosted, 0, hosted.size(), m_hxp.data(), acc);
  std::vector<int> marg;
  for (int pi : hosted) {
    const WindowPoint &p = m_points[static_cast<size_t>(pi)];
    const MapPoint &mp = m_frames[static_cast<size_t>(idx)].kf->points[static_cast<size_t>(p.pointIndex)];
    if (p.inlierResiduals > 0 && p.Hpp >= m_mapper.minIdepthHessianMarginalize && !mp.depthFromPrior) {
      marg.push_back(pi);
    }
  }
  acc.reset(n);
  linearizeRange(m_ctx, m_points, marg, 0, marg.size(), m_hxp.data(), acc);
  schurRange(m_ctx, m_points, marg, 0, marg.size(), m_hxp.data(), 0., acc);
  Eigen::MatrixXd Hm;
  Eigen::VectorXd bm;
  assembleFullSystem(acc, Hm, bm);
  Hm -= acc.Hsc;
  bm -= acc.bsc;
  // DSO adds the keyframe's own (affine) prior to what is marginalised with it.
  const int o = idx * kFrameDims;
  Hm(o + 6, o + 6) += m_affinePriorA;
  Hm(o + 7, o + 7) += m_affinePriorB;
  bm[o + 6] += m_affinePriorA * m_states[static_cast<size_t>(idx)].a;
  bm[o + 7] += m_affinePriorB * m_states[static_cast<size_t>(idx)].b;
  if (!marg.empty()) {
    m_prior.add(0.5 * (Hm + Hm.transpose()), bm, m_states);
  }
}

void WindowOptimizer::removePointsWithKeyframe(int idx)
{
  std::vector<char> remove(m_points.size(), 0);
  for (size_t i = 0; i < m_points.size(); ++i) {
    WindowPoint &p = m_points[i];
    if (p.host == idx) {
      MapPoint &mp = m_frames[static_cast<size_t>(idx)].kf->points[static_cast<size_t>(p.pointIndex)];
      mp.idepth = p.obs.idepth;
      mp.idepthVar = p.Hpp > 0. ? 1. / p.Hpp : std::numeric_limits<double>::infinity();
      mp.status = leavingStatus(mp);
      remove[i] = 1;
      continue;
    }
    for (size_t r = 0; r < p.residuals.size(); ++r) {
      if (p.residuals[r].target == idx) {
        p.residuals.erase(p.residuals.begin() + static_cast<long>(r));
        break;
      }
    }
    if (p.residuals.empty()) {
      // Observed by nothing that stays: it leaves the window with the keyframe (not into the prior).
      MapPoint &mp = m_frames[static_cast<size_t>(p.host)].kf->points[static_cast<size_t>(p.pointIndex)];
      mp.status = leavingStatus(mp);
      remove[i] = 1;
    }
  }
  removePointsIf(remove);
}

void WindowOptimizer::removeKeyframeStates(int idx, bool fixed)
{
  if (fixed) {
    m_gaugeAnchor = m_states[static_cast<size_t>(idx)];
    m_hasAnchor = true;
  }
  m_prior.removeFrame(idx, fixed);
  KeyframePtr kf = m_frames[static_cast<size_t>(idx)].kf;
  kf->frame->cMw = m_states[static_cast<size_t>(idx)].cMw;
  kf->frame->affine.a = m_states[static_cast<size_t>(idx)].a;
  kf->frame->affine.b = m_states[static_cast<size_t>(idx)].b;
  kf->inWindow = false;
  m_frames.erase(m_frames.begin() + idx);
  m_states.erase(m_states.begin() + idx);
  remapAfterFrameRemoval(idx);
  if (m_frames.empty()) {
    m_gaugeKeyframeId = -1;
  }
}

void WindowOptimizer::marginalizeKeyframe(int keyframeId)
{
  m_accCurrent = false;
  int idx = -1;
  for (size_t i = 0; i < m_frames.size(); ++i) {
    if (m_frames[i].kf->id() == keyframeId) {
      idx = static_cast<int>(i);
    }
  }
  if (idx < 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           where(__LINE__) + "keyframe " + std::to_string(keyframeId) + " is not in the window");
  }
  syncStatesAndPoints();
  prepareContext();
  const bool fixed = idx == gaugeFixedIndex();
  // 1. The keyframe's points: linearise, keep those with a well-constrained inverse depth (DSO
  //    setting_minIdepthH_marg), Schur-complement them into a frame system (DSO marginalizePointsF).
  marginalizeHostedPoints(idx);
  // 2. Points leave the window: hosted ones become marginalised (kept for the global map with their last
  //    inverse depth and variance); residuals of other points into the keyframe are dropped (DSO).
  removePointsWithKeyframe(idx);
  // 3. The keyframe's 8 states (DSO marginalizeFrame).
  removeKeyframeStates(idx, fixed);
}

std::vector<int> WindowOptimizer::keyframesToMarginalize() const
{
  std::vector<int> out;
  const int n = static_cast<int>(m_frames.size());
  if (n == 0) {
    return out;
  }
  std::vector<char> flagged(static_cast<size_t>(n), 0);
  int numFlagged = 0;
  const Frame &newest = *m_frames.back().kf->frame;
  for (int i = 0; i < n; ++i) {
    const Keyframe &kf = *m_frames[static_cast<size_t>(i)].kf;
    size_t in = kf.immature.size(), outPts = 0;
    for (const MapPoint &p : kf.points) {
      (p.status == PointStatus::active ? in : outPts)++;
    }
    // log of the gain ratio a_ji between the newest keyframe and this one (DSO maxLogAffFacInWindow).
    const double logGain = std::log(kf.frame->exposure / newest.exposure) + kf.frame->affine.a - newest.affine.a;
    const bool fewPoints = static_cast<double>(in) < m_mapper.minPointsFractionKept * static_cast<double>(in + outPts);
    if ((fewPoints || std::fabs(logGain) > m_mapper.maxAffineChangeMarginalize) &&
        n - numFlagged > m_mapper.minWindowSize) {
      flagged[static_cast<size_t>(i)] = 1;
      ++numFlagged;
    }
  }
  if (n - numFlagged > m_mapper.windowSize) {
    // DSO distance score: prefer keyframes close to many others but far from the latest one.
    const int latest = n - kProtectedNewestKeyframes;
    double best = std::numeric_limits<double>::infinity();
    int chosen = -1;
    for (int i = 0; i < latest; ++i) {
      if (flagged[static_cast<size_t>(i)] || m_frames[static_cast<size_t>(i)].kf->id() == 0) {
        continue;
      }
      const SE3d &ci = m_states[static_cast<size_t>(i)].cMw;
      double score = 0.;
      for (int j = 0; j <= latest; ++j) {
        if (j != i) {
          score +=
              1. / (kDistanceScoreEpsilon + (m_states[static_cast<size_t>(j)].cMw * ci.inverse()).translation().norm());
        }
      }
      score *= -std::sqrt((m_states[static_cast<size_t>(latest)].cMw * ci.inverse()).translation().norm());
      if (score < best) {
        best = score;
        chosen = i;
      }
    }
    if (chosen >= 0) {
      flagged[static_cast<size_t>(chosen)] = 1;
    }
  }
  for (int i = 0; i < n; ++i) {
    if (flagged[static_cast<size_t>(i)]) {
      out.push_back(m_frames[static_cast<size_t>(i)].kf->id());
    }
  }
  return out;
}

void WindowOptimizer::setCandidatePairs(int host, CandidatePairs &pairs) const
{
  const Frame &fh = *m_frames[static_cast<size_t>(host)].kf->frame;
  const KeyframeState &sh = m_states[static_cast<size_t>(host)];
  for (size_t t = 0; t < m_frames.size(); ++t) {
    if (static_cast<int>(t) != host) {
      const KeyframeState &st = m_states[t];
      pairs[t].set(sh.cMw, sh.a, sh.b, fh.exposure, st.cMw, st.a, st.b, m_frames[t].kf->frame->exposure);
    }
  }
}

void WindowOptimizer::evaluateCandidate(int host, const CandidatePairs &pairs, const PointObservation &obs,
                                        double &energy, double &H, double &b, int &inliers) const
{
  energy = H = b = 0.;
  inliers = 0;
  PatternLinearization lin;
  for (size_t t = 0; t < m_frames.size(); ++t) {
    if (static_cast<int>(t) == host) {
      continue;
    }
    double e = 0.;
    const ResidualState state =
        evaluatePattern(m_settings, m_frames[t].kf->frame->pyramid.level(0), pairs[t], obs, e, &lin);
    energy += e;
    if (state != ResidualState::inlier) {
      continue;
    }
    ++inliers;
    for (int k = 0; k < kPatternSize; ++k) {
      const double w = lin.weight[static_cast<size_t>(k)];
      const double j = lin.J(k, kRelativeDims - 1);
      H += w * j * j;
      b += w * j * lin.r[static_cast<size_t>(k)];
    }
  }
}

PointActivationResult WindowOptimizer::optimizeNewPoint(int hostKeyframeId, double u, double v, double idepth,
                                                        const std::array<float, kPatternSize> &patch,
                                                        const std::array<float, kPatternSize> &weight, int iterations,
                                                        double priorIdepth, double priorWeight) const
{
  int host = -1;
  for (size_t i = 0; i < m_frames.size(); ++i) {
    if (m_frames[i].kf->id() == hostKeyframeId) {
      host = static_cast<int>(i);
    }
  }
  if (host < 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument, where(__LINE__) + "host keyframe " +
                                                                  std::to_string(hostKeyframeId) +
                                                                  " is not in the window");
  }
  PointObservation obs;
  obs.u = u;
  obs.v = v;
  obs.idepth = idepth;
  obs.patch = patch.data();
  obs.weight = weight.data();
  // The window's states do not change while one point is optimised: its (host, target) pairs are set once.
  CandidatePairs pairs;
  setCandidatePairs(host, pairs);
  // Photometric terms from evaluateCandidate, plus the prior of a re-used point (Hp = photometric Hessian alone).
  auto evaluate = [&](const PointObservation &o, double &e, double &H, double &b, double &Hp, int &in) {
    evaluateCandidate(host, pairs, o, e, H, b, in);
    Hp = H;
    if (priorWeight > 0.) {
      const double d = o.idepth - priorIdepth;
      e += priorWeight * d * d;
      H += priorWeight;
      b += priorWeight * d;
    }
  };
  double energy, H, b, Hphoto;
  int inliers;
  evaluate(obs, energy, H, b, Hphoto, inliers);
  double lambda = kPointInitialLambda;
  for (int it = 0; it < iterations && H > 0.; ++it) {
    const double step = -b / (H * (1. + lambda));
    PointObservation trial = obs;
    trial.idepth += step;
    double e2, H2, b2, Hp2;
    int in2;
    evaluate(trial, e2, H2, b2, Hp2, in2);
    if (e2 < energy) {
      obs = trial;
      energy = e2;
      H = H2;
      b = b2;
      Hphoto = Hp2;
      inliers = in2;
      lambda *= kPointLambdaAccept;
    } else {
      lambda *= kPointLambdaReject;
    }
    if (std::fabs(step) < kPointRelativeStepConverged * std::fabs(obs.idepth)) {
      break;
    }
  }
  PointActivationResult result;
  result.idepth = obs.idepth;
  result.idepthHessian = H;
  result.inlierResiduals = inliers;
  result.energy = energy;
  result.accepted = std::isfinite(energy) && obs.idepth > 0. && inliers >= kMinInlierResidualsActivate &&
                    Hphoto >= m_mapper.minIdepthHessianActivate;
  return result;
}

double WindowOptimizer::idepthHessian(int hostKeyframeId, double u, double v, double idepth,
                                      const std::array<float, kPatternSize> &patch,
                                      const std::array<float, kPatternSize> &weight) const
{
  return optimizeNewPoint(hostKeyframeId, u, v, idepth, patch, weight, 0).idepthHessian;
}
} // namespace hslam
