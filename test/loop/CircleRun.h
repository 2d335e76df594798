// A camera run round a circle, for the loop correction's tests and benchmark: keyframe poses with an odometry drift
// that grows along the run, and the same poses without it (the truth).
#ifndef HSLAM_TEST_LOOP_CIRCLE_RUN_H
#define HSLAM_TEST_LOOP_CIRCLE_RUN_H

#include "math/SE3.h"

#include <cmath>

namespace hslam_test
{
//! Camera \e k (cMw) of a run round a circle of radius 2, a lap every \e placesPerLap keyframes, looking outward, its
//! centre drifting along z by \e drift per keyframe.
inline hslam::SE3d circleCamera(int k, int placesPerLap, double drift)
{
  const double a = 2. * M_PI * k / placesPerLap;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d centre(2. * std::cos(a), 0., 2. * std::sin(a) + drift * k);
  return hslam::SE3d(q, -(q * centre));
}
} // namespace hslam_test

#endif
