/*
 * H-SLAM for ViSP.
 */
/*!
  \file LandmarkSightings.h
  \brief Landmarks seen in metres from keyframes (AprilTags, map/MetricFrame.h), as loop closure's pose graphs take
  them (loop/LoopCorrection.h): the loop component knows nothing of tags, only of poses measured in metres.
*/
#ifndef HSLAM_LOOP_LANDMARK_SIGHTINGS_H
#define HSLAM_LOOP_LANDMARK_SIGHTINGS_H

#include "math/SE3.h"

#include <vector>

namespace hslam
{
//! A keyframe's sighting of a landmark: the landmark's pose in the keyframe's camera, metres.
struct LandmarkSighting {
  int keyframe = -1;
  int landmark = -1; //!< >= 0 (a tag id)
  SE3d cMl;
  double range = 0.; //!< distance camera-landmark, metres (the detector's precision is a share of it)
};

//! The sightings a correction's graph holds, and how metres relate to the map's unit now.
struct LandmarkSightings {
  double metresPerUnit = 0.; //!< the metric frame's scale; 0: not metric, the sightings are not used
  std::vector<LandmarkSighting> sightings;
  bool usable() const { return metresPerUnit > 0. && !sightings.empty(); }
};
} // namespace hslam

#endif
