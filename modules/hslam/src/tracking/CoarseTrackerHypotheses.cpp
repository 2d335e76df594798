/*
 * H-SLAM for ViSP.
 */
// Motion hypotheses and their sequential trial (DSO FullSystem::trackNewCoarse), projection of window points into
// the reference keyframe, status names. See CoarseTracker.h.
#include "tracking/CoarseTracker.h"

#include <cmath>

namespace hslam
{
namespace
{
/*!
  Rotation hypotheses: quaternion (1, d*x, d*y, d*z) with (x, y, z) in {-1, 0, 1}^3 \ {0}, normalised, for each d
  here. DSO tries d = 0.02 (about 2.3 degrees about an axis); the second, larger ring is our addition for faster
  hand-held motion. Failing hypotheses only cost the coarsest level (the residual bound stops them).
*/
constexpr double kCoarseRotationHypothesisSteps[] = {0.02, 0.04};
//! Half of the last motion (DSO's "half motion" hypothesis).
constexpr double kHalfMotion = 0.5;
/*!
  Once the first hypothesis has failed and none has succeeded yet, the others are bounded per level by this
  multiple of the last tracked frame's RMSE (then 1.5x inside track()): without any bound each of the ~57
  hypotheses would run every level to its iteration limit on a frame that cannot be aligned (covered lens,
  cut), seconds per frame. Integration addition, not in DSO (which leaves them unbounded).
*/
constexpr double kHopelessRmseFactor = 5.;
} // namespace

bool projectIntoReference(const SE3d &refMhost, const PinholeIntrinsics &K0, int width, int height, float uHost,
                          float vHost, float idepthHost, float weight, CoarseTrackerPoint &out)
{
  if (!(idepthHost > 0.f) || !std::isfinite(idepthHost)) {
    return false;
  }
  // (R p + t) scaled by the host inverse depth, with p = K^-1 (u, v, 1) / idepth: no division by idepth.
  const Eigen::Vector3d ray((uHost - K0.cx) / K0.fx, (vHost - K0.cy) / K0.fy, 1.);
  const Eigen::Vector3d pt = refMhost.unitQuaternion() * ray + refMhost.translation() * idepthHost;
  if (!(pt[2] > 0.)) {
    return false;
  }
  const double u = K0.fx * pt[0] / pt[2] + K0.cx;
  const double v = K0.fy * pt[1] / pt[2] + K0.cy;
  if (!(u >= 0. && v >= 0. && u <= width - 1. && v <= height - 1.)) {
    return false;
  }
  out.u = static_cast<float>(u);
  out.v = static_cast<float>(v);
  out.idepth = static_cast<float>(idepthHost / pt[2]);
  out.weight = weight;
  return true;
}

const char *coarseTrackingStatusName(CoarseTrackingStatus status)
{
  switch (status) {
  case CoarseTrackingStatus::ok:
    return "ok";
  case CoarseTrackingStatus::noReference:
    return "no reference (or no usable reference point)";
  case CoarseTrackingStatus::tooFewResiduals:
    return "too few residuals inside the new image";
  case CoarseTrackingStatus::worseThanBound:
    return "residual worse than the bound (previous hypothesis)";
  case CoarseTrackingStatus::tooManyOutliers:
    return "more than 60 % outliers at the finest level";
  case CoarseTrackingStatus::implausibleBrightness:
    return "implausible brightness change";
  case CoarseTrackingStatus::notFinite:
    return "non-finite energy or estimate";
  }
  return "unknown";
}

SE3d CoarseTracker::predictConstantVelocity(const CoarseMotionHistory &history)
{
  if (!history.valid) {
    return SE3d();
  }
  // The motion between the last two frames, assumed to repeat (DSO: fh_2_slast = slast_2_sprelast).
  return history.lastMref * history.prelastMref.inverse() * history.lastMref;
}

void CoarseTracker::makeMotionHypotheses(const CoarseMotionHistory &history, std::vector<SE3d> &hypotheses)
{
  hypotheses.clear();
  if (!history.valid) {
    hypotheses.push_back(SE3d());
    return;
  }
  const SE3d lastMprelast = history.lastMref * history.prelastMref.inverse();
  const SE3d constantVelocity = predictConstantVelocity(history);
  hypotheses.push_back(constantVelocity);
  hypotheses.push_back(lastMprelast * lastMprelast * history.lastMref); // a frame was skipped
  hypotheses.push_back(SE3d::exp(kHalfMotion * lastMprelast.log()) * history.lastMref);
  hypotheses.push_back(history.lastMref); // no motion since the last frame
  hypotheses.push_back(SE3d());           // no motion since the reference
  for (double step : kCoarseRotationHypothesisSteps) {
    for (int x = -1; x <= 1; ++x) {
      for (int y = -1; y <= 1; ++y) {
        for (int z = -1; z <= 1; ++z) {
          if (x == 0 && y == 0 && z == 0) {
            continue;
          }
          const Eigen::Quaterniond q(1., step * x, step * y, step * z);
          hypotheses.push_back(constantVelocity * SE3d(q, Eigen::Vector3d::Zero()));
        }
      }
    }
  }
}

void CoarseTracker::lowerHypothesisBound(CoarseRmsePerLevel &achieved, const CoarseTrackingResult &attempt)
{
  for (size_t l = 0; l < achieved.size(); ++l) {
    if (!attempt.success && static_cast<int>(l) == attempt.failedLevel) {
      continue; // the RMSE of the level that failed (collapsed brightness, too many outliers) is no fit
    }
    if (!std::isfinite(achieved[l]) || achieved[l] > attempt.rmse[l]) {
      achieved[l] = attempt.rmse[l];
    }
  }
}

CoarseRmsePerLevel CoarseTracker::recentRmse() const
{
  CoarseRmsePerLevel recent = m_lastRmse;
  for (size_t l = 0; l < recent.size(); ++l) {
    if (!std::isfinite(recent[l]) || m_prelastRmse[l] > m_params.retrackResidualFactor * recent[l]) {
      recent[l] = m_prelastRmse[l];
    }
  }
  return recent;
}

bool CoarseTracker::trackWithHypotheses(const Frame &newFrame, const CoarseMotionHistory &history, SE3d &newMref,
                                        AffineBrightness &affine, CoarseTrackingResult &result)
{
  makeMotionHypotheses(history, m_hypotheses);
  if (history.hasIndirectPose) {
    // Hybrid tracking: the pose of the indirect step (ORB matches) is tried right after the constant-velocity
    // prediction, or first when there is no prediction. Under smooth motion the prediction is the better start: the
    // indirect pose rests on some 20-50 integer FAST pixels, and starting from it the alignment ended elsewhere
    // (slam, 11 point budgets, 7-Scenes / Tsukuba / KITTI: 0.0535 m / 0.259 cm / 0.0240 m first, 0.0520 / 0.258 /
    // 0.0226 second; direct tracking 0.0507 / 0.261 / 0.0222). When the prediction fails its bound (large motion),
    // the indirect pose is next: with every K-th frame (K = 1-8) the same frames were tracked either way.
    const auto at = history.valid ? m_hypotheses.begin() + 1 : m_hypotheses.begin();
    m_hypotheses.insert(at, history.indirectMref);
  }
  const CoarseRmsePerLevel recent = recentRmse();
  CoarseRmsePerLevel achieved;
  achieved.fill(std::numeric_limits<double>::quiet_NaN());
  bool haveOneGood = false;
  int tried = 0;
  CoarseTrackingResult attempt, firstAttempt;
  for (size_t i = 0; i < m_hypotheses.size(); ++i) {
    SE3d pose = m_hypotheses[i];
    AffineBrightness affineTry = history.lastAffine;
    // Each level must be at least about as good as the best so far (bound by 1.5x inside track()).
    const bool good = track(newFrame, pose, affineTry, attempt, &achieved);
    ++tried;
    if (i == 0) {
      firstAttempt = attempt;
      if (!good) {
        for (size_t l = 0; l < achieved.size(); ++l) {
          if (std::isfinite(recent[l])) {
            achieved[l] = kHopelessRmseFactor * recent[l];
          }
        }
      }
    }
    // New winner: a success whose finest RMSE beats the best so far (or the first success).
    if (good && std::isfinite(attempt.rmse[0]) && !(attempt.rmse[0] >= achieved[0])) {
      result = attempt;
      haveOneGood = true;
    }
    if (haveOneGood) {
      lowerHypothesisBound(achieved, attempt);
    }
    // Good enough compared to the last frame: stop (DSO setting_reTrackThreshold).
    if (haveOneGood && achieved[0] < recent[0] * m_params.retrackResidualFactor) {
      break;
    }
  }
  if (!haveOneGood) {
    // m_lastRmse and m_prelastRmse keep the last successful frames' values: the next frame's bound (recentRmse()).
    result = firstAttempt;
    result.hypothesesTried = tried;
    newMref = m_hypotheses[0];
    affine = history.lastAffine;
    return false;
  }
  result.hypothesesTried = tried;
  m_prelastRmse = m_lastRmse;
  m_lastRmse = achieved;
  if (!std::isfinite(m_firstRmse)) {
    m_firstRmse = achieved[0];
  }
  newMref = result.newMref;
  affine = result.affine;
  return true;
}
} // namespace hslam
