/*
 * H-SLAM for ViSP.
 */
/*!
  \file Frame.h
  \brief One tracked frame: timestamp, pose, brightness and its image pyramid.

  Ownership: created by the tracking thread; shared (std::shared_ptr) with mapping when it becomes a keyframe or
  is used to trace immature points. The pyramid and the raw 8-bit rectified image are immutable after creation.
  Pose and brightness are written by the thread that owns the frame at that moment (tracking for a non-keyframe,
  the mapper's window optimisation for a keyframe); readers in another thread go through the system's mutexes.
*/
#ifndef HSLAM_MAP_FRAME_H
#define HSLAM_MAP_FRAME_H

#include "features/ImagePyramid.h"
#include "map/AffineBrightness.h"
#include "math/SE3.h"

#include <visp3/core/vpImage.h>

#include <memory>

namespace hslam
{
struct Frame {
  int id = -1;                //!< 0-based index of the frame in the input sequence
  int keyframeId = -1;        //!< index among keyframes, -1 when not a keyframe
  double timestamp = 0.;      //!< seconds
  double exposure = 1.;       //!< exposure time (any consistent unit; 1 when unknown)
  SE3d cMw;                   //!< world-to-camera transform
  AffineBrightness affine;    //!< brightness parameters (a, b)
  ImagePyramid pyramid;       //!< photometric (irradiance) pyramid used by the direct part
  vpImage<unsigned char> raw; //!< rectified, photometrically RAW 8-bit image (FAST / ORB run on it)
};

using FramePtr = std::shared_ptr<Frame>;
} // namespace hslam

#endif
