/*
 * H-SLAM for ViSP.
 */
#include "tracking/AdaptiveTracking.h"

#include "features/ImagePyramid.h"

#include <cmath>

namespace hslam
{
const char *geometricReasonName(GeometricReason reason)
{
  switch (reason) {
  case GeometricReason::none:
    return "direct";
  case GeometricReason::always:
    return "hybrid";
  case GeometricReason::lost:
    return "lost";
  case GeometricReason::largeMotion:
    return "large motion";
  case GeometricReason::predictionRefused:
    return "prediction refused";
  case GeometricReason::directFailed:
    return "direct failed";
  }
  return "unknown";
}

AdaptiveTrackingPolicy::AdaptiveTrackingPolicy(const vpHSlamParameters::Tracking &params, int width)
    : m_motionThresholdPx(params.adaptiveMotionPx * width / kReferenceWidthPx)
{
}

GeometricReason AdaptiveTrackingPolicy::beforeDirect(bool historyValid, double predictedShiftPx) const
{
  if (historyValid && std::isfinite(predictedShiftPx) && predictedShiftPx > m_motionThresholdPx) {
    return GeometricReason::largeMotion;
  }
  return GeometricReason::none;
}

GeometricReason AdaptiveTrackingPolicy::afterDirect(bool success, const CoarseTrackingResult &result,
                                                    double measuredShiftPx) const
{
  if (!success) {
    return GeometricReason::directFailed;
  }
  if (result.hypothesesTried > 1) {
    return GeometricReason::predictionRefused;
  }
  if (std::isfinite(measuredShiftPx) && measuredShiftPx > m_motionThresholdPx) {
    return GeometricReason::largeMotion;
  }
  return GeometricReason::none;
}
} // namespace hslam
