/*
 * H-SLAM for ViSP.
 */
/*!
  \file Keyframe.h
  \brief A keyframe: its frame (pose, brightness, pyramid) and the points it hosts.

  Ownership: the mapper owns keyframes (std::shared_ptr, so tracking can keep the newest one alive while it is
  the tracking reference). Points are stored by value in their host; a point is addressed by (host keyframe id,
  index), which stays valid because hosted points are never erased while the keyframe lives (status changes
  instead).
*/
#ifndef HSLAM_MAP_KEYFRAME_H
#define HSLAM_MAP_KEYFRAME_H

#include "map/Frame.h"
#include "map/ImmaturePoint.h"
#include "map/MapPoint.h"

#include <memory>
#include <vector>

namespace hslam
{
struct Keyframe {
  FramePtr frame;                      //!< pose cMw, affine (a, b), pyramid, raw image
  std::vector<MapPoint> points;        //!< hosted points (active, marginalised or outlier)
  std::vector<ImmaturePoint> immature; //!< hosted candidates still being traced
  bool inWindow = true;                //!< false once marginalised from the photometric window
  int id() const { return frame->keyframeId; }
};

using KeyframePtr = std::shared_ptr<Keyframe>;
} // namespace hslam

#endif
