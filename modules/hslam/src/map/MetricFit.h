/*
 * H-SLAM for ViSP.
 */
/*!
  \file MetricFit.h
  \brief The robust similarity fit behind the metric frame (map/MetricFrame.h): from a tag's sightings in keyframes
  to the similarity mSw = (s, R, t) from the map's frame to the tag's, in metres.

  Every sighting i relates the two frames: camera centre q_i = tMc_i.t = s R p_i + t (p_i = wMc_i.t) and orientation
  tRc_i = R wRc_i. Steps:
  1. R: each sighting proposes R_i = tRc_i wRc_i^T; the proposal with most others within outlierRotationDeg seeds
     the consensus, the agreeing ones are averaged (quaternion mean), the others refused.
  2. The tag's depth in the map (TagView::depthScale, measured by MetricFrame): a robust mean over the kept sightings
     that have one; it fixes s even when the cameras hardly moved.
  3. s (unless step 2 gave it) and t with R held: least squares on the camera centres about their means; sightings
     missing by more than max(3 robust sigma, outlierDistanceShare x their range) are refused, the fit repeated.
  4. One Gauss-Newton over R (left increment), t and log s with every kept sighting's position and orientation,
     weighted by the detector's precisions, and the depth scale as a prior on log s.
  5. Trust: the relative standard deviation of s from the resulting information, the sightings' part scaled by
     their residuals when those exceed the precisions, must be under maxScaleUncertainty with at least minSightings
     kept.
*/
#ifndef HSLAM_MAP_METRIC_FIT_H
#define HSLAM_MAP_METRIC_FIT_H

#include "math/SE3.h"
#include "math/Sim3.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <vector>

namespace hslam
{
//! One sighting as the fit takes it: the keyframe's SLAM pose and the tag's pose in its camera.
struct TagView {
  SE3d wMc;               //!< keyframe camera to SLAM world (map units)
  SE3d cMt;               //!< tag to camera, metres
  double depthScale = 0.; //!< metres per map unit from the map's points on the tag (0: none measured)
  int depthPoints = 0;    //!< points that measured it
};

//! What the fit gave.
struct MetricFit {
  bool metric = false;           //!< trusted (see MetricFrame.h, step 3)
  bool tagFrame = false;         //!< mSw puts the world in the tag's frame (an id was given)
  Sim3d mSw;                     //!< SLAM world to the output world (metres)
  double scale = 1.;             //!< metres per map unit (s)
  double scaleUncertainty = 1.;  //!< relative standard deviation of s (1: unknown)
  double rmsMetres = 0.;         //!< RMS camera-centre residual of the kept sightings, metres
  double rotationSpreadDeg = 0.; //!< RMS angle of the kept sightings' rotations to the consensus, degrees
  double depthScale = 0.;        //!< the scale the map's points on the tag gave (0: none)
  unsigned int segment = 0;      //!< map segment fitted (MetricFrame::refit: the current one)
  bool allSegments = false;      //!< applies to every segment (a loaded map's frame, localisation-only)
  unsigned int sightings = 0;    //!< sightings fitted (one segment, one tag)
  unsigned int kept = 0;         //!< of which kept (the others refused as outliers)
  std::vector<bool> inlier;      //!< per view given to fitMetricFrame()
};

/*!
  The robust fit of MetricFrame.h on \e views (one tag, one segment). With \e tagFrame false only the scale is
  applied (mSw = (s, I, 0)). Fewer than two views, or all refused: metric false, scale 1.
*/
VISP_EXPORT MetricFit fitMetricFrame(const std::vector<TagView> &views, bool tagFrame,
                                     const vpHSlamParameters::TagFrame &options);

//! Element n/2 of the sorted values (the upper median for an even count); 0 for none.
VISP_EXPORT double upperMedian(std::vector<double> values);
} // namespace hslam

#endif
