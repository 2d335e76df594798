// Conversions between the public vpHSlamTrajectory (ViSP types) and the internal StampedPose list (Eigen).
#ifndef HSLAM_IO_TRAJECTORY_CONVERSION_H
#define HSLAM_IO_TRAJECTORY_CONVERSION_H

#include "io/TrajectoryIo.h"

#include <visp3/hslam/vpHSlamTrajectory.h>

namespace hslam
{
//! Copy the 3x4 block element by element (no re-orthonormalisation: what was read is what is stored).
inline vpHomogeneousMatrix toHomogeneousMatrix(const StampedPose &pose)
{
  vpHomogeneousMatrix wMc;
  for (unsigned int r = 0; r < 3; ++r) {
    for (unsigned int c = 0; c < 3; ++c) {
      wMc[r][c] = pose.wRc(r, c);
    }
    wMc[r][3] = pose.wtc[r];
  }
  return wMc;
}

inline StampedPose toStampedPose(double timestamp, const vpHomogeneousMatrix &wMc)
{
  StampedPose pose;
  pose.timestamp = timestamp;
  for (unsigned int r = 0; r < 3; ++r) {
    for (unsigned int c = 0; c < 3; ++c) {
      pose.wRc(r, c) = wMc[r][c];
    }
    pose.wtc[r] = wMc[r][3];
  }
  return pose;
}

inline std::vector<StampedPose> toStampedPoses(const vpHSlamTrajectory &trajectory)
{
  std::vector<StampedPose> poses;
  poses.reserve(trajectory.size());
  for (size_t i = 0; i < trajectory.size(); ++i) {
    poses.push_back(toStampedPose(trajectory.getTimestamp(i), trajectory.get_wMc(i)));
  }
  return poses;
}

inline vpHSlamTrajectory toTrajectory(const std::vector<StampedPose> &poses)
{
  vpHSlamTrajectory trajectory;
  for (const StampedPose &pose : poses) {
    trajectory.add(pose.timestamp, toHomogeneousMatrix(pose));
  }
  return trajectory;
}
} // namespace hslam

#endif
