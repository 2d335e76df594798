// The map written by tutorial-hslam-dataset: --map-ply (points and keyframe centres, coloured by kind, for
// MeshLab / CloudCompare) and --map-png (a top view of map points and trajectory).
#ifndef HSLAM_TUTORIAL_DATASET_MAP_OUTPUT_H
#define HSLAM_TUTORIAL_DATASET_MAP_OUTPUT_H

#include <visp3/hslam/vpHSlam.h>

#include <string>
#include <vector>

namespace hslam_dataset
{
/*!
  ASCII PLY of the map: one vertex per map point (orange: active in the window, grey: global map) and per keyframe
  camera centre (red), with x y z and red green blue.
  \exception vpHSlamException::fileUnreadable when the file cannot be written.
*/
void writeMapPly(const std::string &path, const std::vector<vpHSlam::MapPoint> &points,
                 const std::vector<vpHSlam::Keyframe> &keyframes);

/*!
  Top view (the plane of largest spread of the trajectory) of the map points and the trajectory, 1000 x 800
  pixels, equal axes; points farther than a few trajectory sizes from it are left out of the framing.
  \exception vpHSlamException::invalidArgument when there is no pose, fileUnreadable when it cannot be written.
*/
void writeMapPng(const std::string &path, const std::vector<vpHSlam::MapPoint> &points,
                 const vpHSlamTrajectory &trajectory);
} // namespace hslam_dataset

#endif
