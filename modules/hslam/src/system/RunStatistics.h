/*
 * H-SLAM for ViSP.
 */
/*!
  \file RunStatistics.h
  \brief Timings and counters of a run (tracking per frame, mapping per keyframe) and process memory.

  Threading: tracking and mapping threads record into it concurrently; one mutex, held for a push_back.
*/
#ifndef HSLAM_SYSTEM_RUN_STATISTICS_H
#define HSLAM_SYSTEM_RUN_STATISTICS_H

#include "tracking/AdaptiveTracking.h"

#include <visp3/core/vpConfig.h>

#include <mutex>
#include <vector>

namespace hslam
{
//! Nearest-rank percentile (q in [0, 1]) of a list of values; 0 for an empty list. Median: q = 0.5.
VISP_EXPORT double percentile(std::vector<double> values, double q);

/*!
  A field of /proc/self/status in megabytes (e.g. "VmHWM:" peak resident set, "VmRSS:" current), 0 when the
  file or the field is missing (non-Linux systems).
*/
VISP_EXPORT double processMemoryMb(const char *field);

//! Monotonic clock, milliseconds.
VISP_EXPORT double nowMs();
//! CPU time consumed by the calling thread, milliseconds (insensitive to other processes; for profiling logs).
VISP_EXPORT double threadCpuMs();

class VISP_EXPORT RunStatistics
{
public:
  void addTrackingMs(double ms);
  void addInitializationMs(double ms);
  void addKeyframeMappingMs(double ms);
  void addFrameMappingMs(double ms);
  //! Hybrid / indirect tracking of one frame: ORB matches, geometric inliers, K at the finest level.
  void addHybridFrame(int matches, int inliers, double geometricWeight);
  //! A frame given a pose, and why its pose used the geometric term (GeometricReason::none: it did not).
  void addPosedFrame(GeometricReason reason);
  //! Real-time mode: a frame whose tracking overlapped a loop correction in the mapping thread.
  void addTrackingMsDuringLoopCorrection(double ms);

  struct Summary {
    double trackingMsMedian = 0., trackingMsP95 = 0., trackingMsMax = 0.;
    double initializationMsMedian = 0.;
    double keyframeMsMedian = 0., keyframeMsP95 = 0.;
    double frameMappingMsMedian = 0.;
    double orbMatchesMedian = 0., orbInliersMedian = 0., geometricWeightMedian = 0.;
    int posedFrames = 0;     //!< frames given a pose (addPosedFrame)
    int geometricFrames = 0; //!< those posed with the geometric term (every reason)
    //! Adaptive tracking: those frames by GeometricReason (largeMotion, predictionRefused, directFailed)
    int geometricLargeMotion = 0, geometricPredictionRefused = 0, geometricDirectFailed = 0;
    int framesDuringLoopCorrection = 0;            //!< frames whose tracking overlapped a loop correction
    double trackingMsMaxDuringLoopCorrection = 0.; //!< the longest of them
  };
  Summary summary() const;
  void clear();

private:
  mutable std::mutex m_mutex;
  std::vector<double> m_trackingMs, m_initializationMs, m_keyframeMs, m_frameMappingMs;
  std::vector<double> m_orbMatches, m_orbInliers, m_geometricWeight;
  int m_posedFrames = 0, m_geometricFrames = 0;
  int m_geometricLargeMotion = 0, m_geometricPredictionRefused = 0, m_geometricDirectFailed = 0;
  int m_framesDuringLoopCorrection = 0;
  double m_trackingMsMaxDuringLoopCorrection = 0.;
};
} // namespace hslam

#endif
