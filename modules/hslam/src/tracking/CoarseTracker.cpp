/*
 * H-SLAM for ViSP.
 */
// Coarse-to-fine direct alignment (DSO CoarseTracker: makeCoarseDepthL0, calcRes, calcGSSSE, trackNewestCoarse),
// re-implemented; see CoarseTracker.h for the model and the conventions.
#include "tracking/CoarseTracker.h"
#include "common/TextParsing.h"

#include "common/RobustWeights.h"
#include "tracking/PoseOnlyOptimizer.h"
#include <visp3/hslam/vpHSlamException.h>

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>

namespace hslam
{
namespace
{
//! DSO: the cutoff of a level is doubled while more than this share of its residuals is saturated...
constexpr double kMaxSaturatedRatio = 0.6;
//! Joint objective: floors of the estimated variances s_p^2 (intensity^2) and s_g^2 (pixels^2), so that a frame
//! with near-zero residuals (synthetic, static) does not give one term an unbounded weight.
constexpr double kMinPhotometricVariance = 1.;
constexpr double kMinGeometricVariance = 0.25;
//! ... up to this factor of the base cutoff (DSO: levelCutoffRepeat < 50).
constexpr float kMaxCutoffRepeat = 50.f;
//! Levenberg damping: start, and the value below which the step is extrapolated (DSO trackNewestCoarse).
constexpr double kInitialLambda = 0.01;
constexpr double kLambdaExtrapolationLimit = 0.001;
//! Damping factor on an accepted / rejected step (DSO).
constexpr double kLambdaOnAccept = 0.5;
constexpr double kLambdaOnReject = 4.0;
//! A level stops when the scaled increment norm falls to this (DSO).
constexpr double kMinIncrementNorm = 1e-3;
//! A level fails when its RMSE exceeds this factor of the given bound (DSO: 1.5 x minResForAbort).
constexpr double kAbortResidualFactor = 1.5;
//! Brightness change relative to the reference judged implausible (DSO: |log a_ji| > 1.5, |b_ji| > 200).
constexpr double kMaxLogGainChange = 1.5;
constexpr double kMaxOffsetChange = 200.;
//! A level with fewer residuals in the new image is a failure (own choice: the 8-dim system needs many more).
constexpr int kCoarseMinResiduals = 20;
//! Flow indicators sample every n-th level-0 point (DSO: i % 32 == 0) and divide by (count + 0.1).
constexpr int kFlowSampleStride = 32;
constexpr double kFlowSampleRegulariser = 0.1;
//! Warped points must have this margin to the border of the new image (DSO: 2 < Ku < w - 3).
constexpr float kTargetBorder = 2.f;
/*!
  DSO's variable scaling of the 8-dim step (SCALE_XI_ROT = 1 on the first three twist entries, SCALE_XI_TRANS =
  0.5 on the last three, SCALE_A = 10, SCALE_B = 1000): only the convergence test and the affine priors see it,
  the damped Gauss-Newton step itself is invariant to a diagonal scaling.
*/
constexpr double kStepScale[8] = {1., 1., 1., 0.5, 0.5, 0.5, 10., 1000.};
constexpr int kIndexA = 6;
constexpr int kIndexB = 7;

[[noreturn]] void throwError(vpHSlamException::ErrorCode code, int line, const std::string &what)
{
  throwAt(code, __FILE__, static_cast<std::size_t>(line), "CoarseTracker: " + what);
}

inline double nan()
{
  return std::numeric_limits<double>::quiet_NaN();
}
} // namespace

CoarseTracker::ResidualStats &CoarseTracker::ResidualStats::operator+=(const ResidualStats &o)
{
  energy += o.energy;
  numTerms += o.numTerms;
  numSaturated += o.numSaturated;
  numAboveBaseCutoff += o.numAboveBaseCutoff;
  shiftT += o.shiftT;
  shiftR += o.shiftR;
  shiftRT += o.shiftRT;
  shiftSamples += o.shiftSamples;
  return *this;
}

CoarseTracker::CoarseTracker(const vpHSlamParameters::Tracker &params, bool photometricCalibration)
    : m_params(params), m_photometricCalibration(photometricCalibration), m_firstRmse(nan())
{
  if (m_params.iterationsPerLevel.empty()) {
    throwError(vpHSlamException::invalidArgument, __LINE__, "Tracker::iterationsPerLevel is empty");
  }
  if (!(m_params.huberThreshold > 0.) || !(m_params.coarseCutoffResidual > 0.)) {
    throwError(vpHSlamException::invalidArgument, __LINE__,
               "Tracker::huberThreshold and Tracker::coarseCutoffResidual must be > 0");
  }
  // DSO starts with a large "last RMSE" so the first frame accepts its first good hypothesis.
  constexpr double kInitialLastRmse = 100.;
  m_lastRmse.fill(kInitialLastRmse);
  m_prelastRmse.fill(kInitialLastRmse);
}

void CoarseTracker::setWarp(int level, const PyramidLevel &target, const SE3d &newMref, const AffineBrightness &affine,
                            double newExposure)
{
  const PinholeIntrinsics &K = m_levels[static_cast<size_t>(level)].K;
  Eigen::Matrix3d Kinv = Eigen::Matrix3d::Identity();
  Kinv(0, 0) = 1. / K.fx;
  Kinv(1, 1) = 1. / K.fy;
  Kinv(0, 2) = -K.cx / K.fx;
  Kinv(1, 2) = -K.cy / K.fy;
  m_warp.Kinv = Kinv.cast<float>();
  m_warp.RKinv = (newMref.rotationMatrix() * Kinv).cast<float>();
  m_warp.t = newMref.translation().cast<float>();
  double aji = 1., bji = 0.;
  AffineBrightness::transfer(m_refExposure, m_refAffine, newExposure, affine, aji, bji);
  m_warp.aji = static_cast<float>(aji);
  m_warp.bji = static_cast<float>(bji);
  m_warp.refB = static_cast<float>(m_refAffine.b);
  m_warp.fx = static_cast<float>(K.fx);
  m_warp.fy = static_cast<float>(K.fy);
  m_warp.cx = static_cast<float>(K.cx);
  m_warp.cy = static_cast<float>(K.cy);
  m_warp.baseCutoff = static_cast<float>(m_params.coarseCutoffResidual);
  m_warp.target = &target;
}

void CoarseTracker::computeResiduals(int level, int begin, int end, float cutoff, ResidualStats &stats)
{
  const LevelData &L = m_levels[static_cast<size_t>(level)];
  const Warp &W = m_warp;
  const PyramidLevel &target = *W.target;
  const float huber = static_cast<float>(m_params.huberThreshold);
  // Energy of a residual exactly at the cutoff: saturated residuals count with it (DSO).
  const float maxEnergy = 2.f * huber * cutoff - huber * huber;
  const bool sampleFlow = (level == 0);
  // Blocks of points: each block is projected and its interpolation pixels prefetched, then read (the same
  // arithmetic in the same order as one pass; reading right after projecting waited on one cache miss at a time).
  constexpr int kBlock = 16;
  float blockKu[kBlock], blockKv[kBlock];
  bool blockInside[kBlock];
  for (int first = begin; first < end; first += kBlock) {
    const int last = std::min(end, first + kBlock);
    for (int i = first; i < last; ++i) {
      const size_t k = static_cast<size_t>(i);
      const int b = i - first;
      const float id = L.pidepth[k];
      const Eigen::Vector3f pixel(L.pu[k], L.pv[k], 1.f);
      // Point in the new camera scaled by the reference inverse depth: (R p + t) * id, with p = K^-1 x / id.
      const Eigen::Vector3f pt = W.RKinv * pixel + W.t * id;
      const float u = pt[0] / pt[2];
      const float v = pt[1] / pt[2];
      const float Ku = W.fx * u + W.cx;
      const float Kv = W.fy * v + W.cy;
      const float newIdepth = id / pt[2];

      if (sampleFlow && i % kFlowSampleStride == 0) {
        // Mean squared pixel shift of the translation alone (both signs), of the rotation alone and of both (DSO).
        const Eigen::Vector3f ray = W.Kinv * pixel;
        const Eigen::Vector3f rotated = W.RKinv * pixel;
        const Eigen::Vector3f candidates[5] = {ray + W.t * id, ray - W.t * id, rotated, pt, rotated - W.t * id};
        float shifts[5];
        for (int c = 0; c < 5; ++c) {
          const float du = W.fx * candidates[c][0] / candidates[c][2] + W.cx - pixel[0];
          const float dv = W.fy * candidates[c][1] / candidates[c][2] + W.cy - pixel[1];
          shifts[c] = du * du + dv * dv;
        }
        stats.shiftT += static_cast<double>(shifts[0] + shifts[1]);
        stats.shiftR += static_cast<double>(2.f * shifts[2]);
        stats.shiftRT += static_cast<double>(shifts[3] + shifts[4]);
        stats.shiftSamples += 2;
      }

      // The warp's buffers are read by accumulate() only where the weight is set below.
      m_bufWeight[k] = 0.f;
      m_bufIdepth[k] = newIdepth;
      m_bufU[k] = u;
      m_bufV[k] = v;
      blockKu[b] = Ku;
      blockKv[b] = Kv;
      blockInside[b] = newIdepth > 0.f && target.isInside(Ku, Kv, kTargetBorder);
      if (blockInside[b]) {
        target.prefetch(Ku, Kv);
      }
    }
    for (int i = first; i < last; ++i) {
      const size_t k = static_cast<size_t>(i);
      const int b = i - first;
      if (!blockInside[b]) {
        continue;
      }
      const Eigen::Vector3f hit = target.interpolate(blockKu[b], blockKv[b]);
      if (!std::isfinite(hit[0])) {
        continue;
      }
      const float refColor = L.pcolor[k];
      const float residual = hit[0] - (W.aji * refColor + W.bji);
      const float absRes = std::fabs(residual);
      ++stats.numTerms;
      if (absRes > W.baseCutoff) {
        ++stats.numAboveBaseCutoff;
      }
      if (absRes > cutoff) {
        stats.energy += static_cast<double>(maxEnergy);
        ++stats.numSaturated;
        continue;
      }
      const float hw = huberWeight(absRes, huber);
      stats.energy += static_cast<double>(hw * residual * residual * (2.f - hw));
      m_bufDx[k] = hit[1];
      m_bufDy[k] = hit[2];
      m_bufResidual[k] = residual;
      m_bufWeight[k] = hw;
      m_bufRefColor[k] = refColor;
    }
  }
}

void CoarseTracker::accumulate(int begin, int end, NormalEquations8 &eq) const
{
  const Warp &W = m_warp;
  NormalEquations8::Vec9f Jr;
  for (int i = begin; i < end; ++i) {
    const size_t k = static_cast<size_t>(i);
    const float weight = m_bufWeight[k];
    if (weight == 0.f) {
      continue;
    }
    // d r / d (twist, a, b) for newMref <- exp(twist) newMref: image gradient times the derivative of the
    // projection of the moved point (translation first), then the affine terms (see CoarseTracker.h).
    const float gx = m_bufDx[k] * W.fx;
    const float gy = m_bufDy[k] * W.fy;
    const float u = m_bufU[k];
    const float v = m_bufV[k];
    const float id = m_bufIdepth[k];
    Jr[0] = id * gx;
    Jr[1] = id * gy;
    Jr[2] = -id * (u * gx + v * gy);
    Jr[3] = -(u * v * gx + (1.f + v * v) * gy);
    Jr[4] = (1.f + u * u) * gx + u * v * gy;
    Jr[5] = u * gy - v * gx;
    Jr[6] = W.aji * (W.refB - m_bufRefColor[k]);
    Jr[7] = -1.f;
    Jr[8] = m_bufResidual[k];
    eq.add(Jr, weight);
  }
}

double CoarseTracker::priorEnergy(const AffineBrightness &affine) const
{
  const double wA = m_photometricCalibration ? m_params.affinePriorACalibrated : m_params.affinePriorA;
  const double wB = m_photometricCalibration ? m_params.affinePriorBCalibrated : m_params.affinePriorB;
  const double sa = affine.a / kStepScale[kIndexA];
  const double sb = affine.b / kStepScale[kIndexB];
  return wA * sa * sa + wB * sb * sb;
}

CoarseTracker::ResidualStats CoarseTracker::evaluate(int level, const PyramidLevel &target, const SE3d &newMref,
                                                     const AffineBrightness &affine, double newExposure, float cutoff)
{
  setWarp(level, target, newMref, affine, newExposure);
  ResidualStats stats;
  computeResiduals(level, 0, m_levels[static_cast<size_t>(level)].numPoints, cutoff, stats);
  return stats;
}

void CoarseTracker::buildSystem(int level, const ResidualStats &stats, const AffineBrightness &affine,
                                Eigen::Matrix<double, 8, 8> &H, Eigen::Matrix<double, 8, 1> &b) const
{
  NormalEquations8 eq;
  accumulate(0, m_levels[static_cast<size_t>(level)].numPoints, eq);
  eq.flush();
  // The objective is the mean energy (DSO normalises by the residual count), priors included.
  const double invN = 1. / std::max(1, stats.numTerms);
  H = eq.H() * invN;
  b = eq.b() * invN;
  const double wA = m_photometricCalibration ? m_params.affinePriorACalibrated : m_params.affinePriorA;
  const double wB = m_photometricCalibration ? m_params.affinePriorBCalibrated : m_params.affinePriorB;
  const double hA = wA / (kStepScale[kIndexA] * kStepScale[kIndexA]) * invN;
  const double hB = wB / (kStepScale[kIndexB] * kStepScale[kIndexB]) * invN;
  H(kIndexA, kIndexA) += hA;
  H(kIndexB, kIndexB) += hB;
  b(kIndexA) += hA * affine.a;
  b(kIndexB) += hB * affine.b;
}

CoarseTracker::ResidualStats CoarseTracker::evaluateWithCutoffRepeat(int level, const PyramidLevel &target,
                                                                     const SE3d &newMref,
                                                                     const AffineBrightness &affine, double newExposure,
                                                                     float baseCutoff, float &cutoffRepeat)
{
  cutoffRepeat = 1.f;
  ResidualStats stats = evaluate(level, target, newMref, affine, newExposure, baseCutoff);
  while (stats.numTerms > 0 && static_cast<double>(stats.numSaturated) > kMaxSaturatedRatio * stats.numTerms &&
         cutoffRepeat < kMaxCutoffRepeat) {
    cutoffRepeat *= 2.f;
    stats = evaluate(level, target, newMref, affine, newExposure, baseCutoff * cutoffRepeat);
  }
  return stats;
}

CoarseTracker::LevelWeights CoarseTracker::levelWeights(int stepFromCoarsest, const ResidualStats &stats) const
{
  // Joint objective (GeometricTerm): photometric mean energy / s_p^2 + K_l E_g / (n_g s_g^2); without a
  // geometric term the weights are not applied at all (pure DSO alignment, bit for bit).
  LevelWeights weights;
  weights.joint = m_geometric != nullptr && !m_geometric->Xref.empty();
  if (weights.joint) {
    const double sp2 = std::max(stats.energy / stats.numTerms, kMinPhotometricVariance);
    weights.K = geometricWeight(stepFromCoarsest, m_geometric->inliers);
    weights.wp = 1. / sp2;
    weights.wg = (m_geometric->poseFromGeometryOnly ? 1. : weights.K) /
                 ((m_geometric->count > 0. ? m_geometric->count : static_cast<double>(m_geometric->Xref.size())) *
                  std::max(m_geometric->sigma2Px, kMinGeometricVariance));
  }
  return weights;
}

double CoarseTracker::levelObjective(const LevelWeights &weights, const ResidualStats &stats,
                                     const AffineBrightness &affine, const SE3d &newMref) const
{
  const double photometric = (stats.energy + priorEnergy(affine)) / stats.numTerms;
  return weights.joint ? weights.wp * photometric + weights.wg * geometricEnergy(*m_geometric, m_K0, newMref)
                       : photometric;
}

void CoarseTracker::levelSystem(int level, const LevelWeights &weights, const ResidualStats &stats,
                                const AffineBrightness &affine, const SE3d &newMref, Eigen::Matrix<double, 8, 8> &H,
                                Eigen::Matrix<double, 8, 1> &b) const
{
  buildSystem(level, stats, affine, H, b);
  if (!weights.joint) {
    return;
  }
  H *= weights.wp;
  b *= weights.wp;
  if (m_geometric->poseFromGeometryOnly) {
    H.topRows<6>().setZero();
    H.leftCols<6>().setZero();
    b.head<6>().setZero();
  }
  Eigen::Matrix<double, 8, 8> Hg = Eigen::Matrix<double, 8, 8>::Zero();
  Eigen::Matrix<double, 8, 1> bg = Eigen::Matrix<double, 8, 1>::Zero();
  geometricEnergy(*m_geometric, m_K0, newMref, &Hg, &bg);
  H += weights.wg * Hg;
  b += weights.wg * bg;
}

void CoarseTracker::optimizeLevel(int level, const PyramidLevel &target, double newExposure, float cutoff,
                                  const LevelWeights &weights, SE3d &newMref, AffineBrightness &affine,
                                  ResidualStats &stats, int &iterations)
{
  double objectiveOld = levelObjective(weights, stats, affine, newMref);
  Eigen::Matrix<double, 8, 8> H;
  Eigen::Matrix<double, 8, 1> b;
  levelSystem(level, weights, stats, affine, newMref, H, b);
  double lambda = kInitialLambda;
  const size_t iterIndex = std::min(static_cast<size_t>(level), m_params.iterationsPerLevel.size() - 1);
  const int maxIterations = m_params.iterationsPerLevel[iterIndex];
  for (int it = 0; it < maxIterations; ++it) {
    ++iterations;
    Eigen::Matrix<double, 8, 8> Hl = H;
    Hl.diagonal() *= (1. + lambda);
    Eigen::Matrix<double, 8, 1> inc = Hl.ldlt().solve(-b);
    // DSO: with little damping the step is lengthened a little (fourth root of the damping ratio).
    if (lambda < kLambdaExtrapolationLimit) {
      inc *= std::sqrt(std::sqrt(kLambdaExtrapolationLimit / lambda));
    }
    if (!inc.allFinite()) {
      inc.setZero();
    }
    const SE3d candidate = SE3d::exp(inc.head<6>()) * newMref;
    AffineBrightness candidateAffine = affine;
    candidateAffine.a += inc[kIndexA];
    candidateAffine.b += inc[kIndexB];
    const ResidualStats statsNew = evaluate(level, target, candidate, candidateAffine, newExposure, cutoff);
    const double objectiveNew = statsNew.numTerms >= kCoarseMinResiduals
                                    ? levelObjective(weights, statsNew, candidateAffine, candidate)
                                    : std::numeric_limits<double>::infinity();
    if (objectiveNew < objectiveOld) {
      newMref = candidate;
      affine = candidateAffine;
      stats = statsNew;
      objectiveOld = objectiveNew;
      levelSystem(level, weights, stats, affine, newMref, H, b);
      lambda *= kLambdaOnAccept;
    } else {
      lambda *= kLambdaOnReject;
      lambda = std::max(lambda, kLambdaExtrapolationLimit);
    }
    Eigen::Matrix<double, 8, 1> scaled;
    for (int j = 0; j < 8; ++j) {
      scaled[j] = inc[j] / kStepScale[j];
    }
    if (!(scaled.norm() > kMinIncrementNorm)) {
      break;
    }
  }
}

namespace
{
//! The RMSE, flow indicators and inlier ratio of a finished level (\e stats describes the kept state) into \e result.
void recordLevel(int level, const CoarseTracker::ResidualStats &stats, CoarseTrackingResult &result)
{
  const double rmse = std::sqrt(stats.energy / std::max(1, stats.numTerms));
  result.rmse[static_cast<size_t>(level)] = rmse;
  result.flowT = stats.shiftT / (stats.shiftSamples + kFlowSampleRegulariser);
  result.flowR = stats.shiftR / (stats.shiftSamples + kFlowSampleRegulariser);
  result.flowRT = stats.shiftRT / (stats.shiftSamples + kFlowSampleRegulariser);
  result.residuals = stats.numTerms;
  result.inlierRatio = stats.numTerms > 0 ? 1. - static_cast<double>(stats.numAboveBaseCutoff) / stats.numTerms : 0.;
}
} // namespace

bool CoarseTracker::brightnessPlausible(double newExposure, const AffineBrightness &affine) const
{
  double aji = 1., bji = 0.;
  AffineBrightness::transfer(m_refExposure, m_refAffine, newExposure, affine, aji, bji);
  return !(!(aji > 0.) || std::fabs(std::log(aji)) > kMaxLogGainChange || std::fabs(bji) > kMaxOffsetChange);
}

bool CoarseTracker::track(const Frame &newFrame, SE3d &newMref, AffineBrightness &affine, CoarseTrackingResult &result,
                          const CoarseRmsePerLevel *abortRmse)
{
  result = CoarseTrackingResult();
  result.hypothesesTried = 1;
  result.newMref = newMref;
  result.affine = affine;
  if (m_numLevels == 0 || m_levels[0].numPoints == 0) {
    result.status = CoarseTrackingStatus::noReference;
    return false;
  }
  const ImagePyramid &pyr = newFrame.pyramid;
  if (pyr.numLevels() < 1 || pyr.level(0).width != m_levels[0].width || pyr.level(0).height != m_levels[0].height) {
    throwError(vpHSlamException::invalidImage, __LINE__,
               "new frame's pyramid does not match the reference (" + std::to_string(m_levels[0].width) + "x" +
                   std::to_string(m_levels[0].height) + ")");
  }
  const int levels = std::min(m_numLevels, pyr.numLevels());
  result.numLevels = levels;
  const float baseCutoff = static_cast<float>(m_params.coarseCutoffResidual);
  const double exposure = newFrame.exposure;

  SE3d current = newMref;
  AffineBrightness currentAffine = affine;
  bool haveRepeated = false;
  auto fail = [&](CoarseTrackingStatus status, int level) {
    result.status = status;
    result.failedLevel = level;
    result.newMref = current;
    result.affine = currentAffine;
    return false;
  };
  const bool geometryOnly = m_geometric != nullptr && m_geometric->poseFromGeometryOnly;

  for (int lvl = levels - 1; lvl >= 0; --lvl) {
    const PyramidLevel &target = pyr.level(lvl);
    float cutoffRepeat = 1.f;
    ResidualStats stats =
        evaluateWithCutoffRepeat(lvl, target, current, currentAffine, exposure, baseCutoff, cutoffRepeat);
    if (stats.numTerms < kCoarseMinResiduals) {
      return fail(CoarseTrackingStatus::tooFewResiduals, lvl);
    }
    const LevelWeights weights = levelWeights(levels - 1 - lvl, stats);
    if (weights.joint && lvl == 0) {
      result.geometricWeight = weights.K;
    }
    optimizeLevel(lvl, target, exposure, baseCutoff * cutoffRepeat, weights, current, currentAffine, stats,
                  result.iterations);
    recordLevel(lvl, stats, result);
    const double rmse = result.rmse[static_cast<size_t>(lvl)];
    if (!std::isfinite(rmse) || !current.translation().allFinite()) {
      return fail(CoarseTrackingStatus::notFinite, lvl);
    }
    if (!geometryOnly && abortRmse != nullptr && rmse > kAbortResidualFactor * (*abortRmse)[static_cast<size_t>(lvl)]) {
      return fail(CoarseTrackingStatus::worseThanBound, lvl);
    }
    // DSO checks the brightness after every level: a frame that cannot be aligned (covered lens) is matched by
    // a vanishing gain at the coarsest level already; going on would cost every finer level for nothing.
    if (!brightnessPlausible(exposure, currentAffine)) {
      return fail(CoarseTrackingStatus::implausibleBrightness, lvl);
    }
    // DSO: a level that needed a larger cutoff is run once more (the pose is now better, the cutoff resets).
    if (cutoffRepeat > 1.f && !haveRepeated) {
      ++lvl;
      haveRepeated = true;
    }
  }

  if (!geometryOnly && 1. - result.inlierRatio > kMaxSaturatedRatio) {
    return fail(CoarseTrackingStatus::tooManyOutliers, 0);
  }
  if (!brightnessPlausible(exposure, currentAffine)) {
    return fail(CoarseTrackingStatus::implausibleBrightness, 0);
  }
  result.success = true;
  result.status = CoarseTrackingStatus::ok;
  result.newMref = current;
  result.affine = currentAffine;
  newMref = current;
  affine = currentAffine;
  return true;
}
} // namespace hslam
