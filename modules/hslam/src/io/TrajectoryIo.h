// Trajectory and ground-truth file formats (TUM, KITTI, EuRoC ASL), on Eigen types.
//
// The public vpHSlamTrajectory wraps these functions with ViSP types; the evaluation code (src/eval/) uses them
// directly. Every reader names file:line in its errors (vpHSlamException) and never skips a line silently.
#ifndef HSLAM_IO_TRAJECTORY_IO_H
#define HSLAM_IO_TRAJECTORY_IO_H

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace hslam
{
//! One camera pose of a trajectory: camera-to-world rotation and camera centre in the world, at a time in seconds.
struct StampedPose {
  double timestamp = 0.;                             //!< seconds
  Eigen::Matrix3d wRc = Eigen::Matrix3d::Identity(); //!< camera-to-world rotation
  Eigen::Vector3d wtc = Eigen::Vector3d::Zero();     //!< camera centre in world coordinates (metres or dataset unit)
};

//! A quaternion read from a file must have |norm - 1| below this; it is then normalised. Files print about 6-9
//! digits, so a larger deviation means a wrong column order or a corrupt line, not rounding.
constexpr double kQuaternionNormTolerance = 1e-3;
//! A 3x3 rotation read from a file (KITTI) must satisfy max|R^T R - I| below this (7 printed digits give ~1e-7).
constexpr double kRotationOrthonormalityTolerance = 1e-3;

/*!
  Read a TUM trajectory: one pose per line "t tx ty tz qx qy qz qw" (any blanks between fields), '#' starts a
  comment, blank lines are skipped. Timestamps must increase strictly. The quaternion is normalised.
  \throw vpHSlamException naming file:line (missing file, wrong field count, bad number, non-unit quaternion,
  non-increasing time).
*/
VISP_EXPORT std::vector<StampedPose> readTumTrajectory(const std::string &path);

/*!
  Write a TUM trajectory with a one-line header comment. Timestamps are printed with 9 decimals (nanoseconds),
  translations with 10 significant digits, the quaternion (qw >= 0) with 9 decimals. The stream is flushed and
  checked: a full disk or a closed file raises an error instead of losing lines.
*/
VISP_EXPORT void writeTumTrajectory(const std::string &path, const std::vector<StampedPose> &poses);

/*!
  Read a KITTI odometry trajectory: 12 numbers per row, the 3x4 matrix [wRc | wtc] row by row. The rotation is
  kept exactly as printed (no re-orthonormalisation, so a write/read round trip is exact) after checking it is a
  rotation to kRotationOrthonormalityTolerance.
  \param timesPath : optional KITTI times.txt (one time in seconds per line, as many as poses); empty for none.
  \param frameRate : without a times file, timestamp = index / frameRate when frameRate > 0, else the row index.
*/
VISP_EXPORT std::vector<StampedPose> readKittiTrajectory(const std::string &path, const std::string &timesPath = "",
                                                         double frameRate = 0.);

//! Write a KITTI trajectory (12 numbers per row, scientific notation with 9 decimals). Timestamps are not stored.
VISP_EXPORT void writeKittiTrajectory(const std::string &path, const std::vector<StampedPose> &poses);

/*!
  Read an EuRoC ASL ground-truth csv (state_groundtruth_estimate0/data.csv): per row, timestamp in nanoseconds,
  p_RS_R (x y z, metres), q_RS (w x y z), then velocities and biases (ignored). Poses are the BODY (IMU) frame in
  the world: apply the sensor extrinsics (readEurocSensorExtrinsics) to get camera poses.
*/
VISP_EXPORT std::vector<StampedPose> readEurocGroundTruth(const std::string &csvPath);

/*!
  Read T_BS (sensor-to-body, i.e. bMc for a camera: p_body = T_BS p_sensor) from an EuRoC sensor.yaml with
  cv::FileStorage ("T_BS: {rows: 4, cols: 4, data: [16 numbers]}").
*/
VISP_EXPORT Eigen::Matrix4d readEurocSensorExtrinsics(const std::string &sensorYamlPath);

//! wMs = wMb * bMs for every pose (body trajectory to sensor trajectory, EuRoC T_BS = bMs).
VISP_EXPORT void applyBodyToSensor(std::vector<StampedPose> &poses, const Eigen::Matrix4d &bMs);

// Checks shared by the readers (TrajectoryIo.cpp, TrajectoryEuroc.cpp); errors name path:line.

/*!
  Rotation of a quaternion read from a file, given as (w, x, y, z) whatever the file's column order.
  \param columns : the file's quaternion columns, for the message ("qx qy qz qw").
  \throw vpHSlamException::parseError when |norm - 1| > kQuaternionNormTolerance; otherwise it is normalised.
*/
Eigen::Matrix3d rotationFromFileQuaternion(double w, double x, double y, double z, const std::string &columns,
                                           const std::string &path, size_t line);

//! Empty when \e R is a rotation (max|R^T R - I| <= kRotationOrthonormalityTolerance, det > 0), else what is wrong.
std::string rotationDefect(const Eigen::Matrix3d &R);

//! Throws vpHSlamException::invalidTimestamps naming path:line unless \e timestamp follows the last pose's.
void checkIncreasing(const std::vector<StampedPose> &poses, double timestamp, const std::string &path, size_t line);

} // namespace hslam

#endif
