// TUM and KITTI trajectory formats. EuRoC lives in TrajectoryEuroc.cpp.
#include "io/TrajectoryIo.h"
#include "io/TrajectoryText.h"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <fstream>
#include <sstream>

namespace hslam
{
namespace
{
using trajectory_text::fail;

//! TUM: t tx ty tz qx qy qz qw.
constexpr size_t kTumFieldCount = 8;
//! KITTI: 3x4 matrix row by row.
constexpr size_t kKittiFieldCount = 12;
//! Printed precision of the writers (see writeTumTrajectory's documentation).
constexpr int kTimestampDecimals = 9;
constexpr int kTranslationSignificantDigits = 10;
constexpr int kQuaternionDecimals = 9;
constexpr int kKittiDecimals = 9;

std::ifstream openForReading(const std::string &path)
{
  std::ifstream file(path);
  if (!file.is_open()) {
    fail(vpHSlamException::fileNotFound, path, 0, "cannot open the trajectory file (missing or unreadable)");
  }
  return file;
}

void checkIncreasing(const std::vector<StampedPose> &poses, double timestamp, const std::string &path, size_t line)
{
  if (!poses.empty() && !(timestamp > poses.back().timestamp)) {
    std::ostringstream msg;
    msg.precision(17);
    msg << "timestamp " << timestamp << " does not increase (previous " << poses.back().timestamp << ")";
    fail(vpHSlamException::invalidTimestamps, path, line, msg.str());
  }
}
} // namespace

std::vector<StampedPose> readTumTrajectory(const std::string &path)
{
  std::ifstream file = openForReading(path);
  std::vector<StampedPose> poses;
  std::string raw;
  size_t lineNumber = 0;
  while (std::getline(file, raw)) {
    ++lineNumber;
    const std::string line = trajectory_text::stripComment(raw);
    if (line.empty()) {
      continue;
    }
    const std::vector<std::string> fields = trajectory_text::splitFields(line, " \t,");
    if (fields.size() != kTumFieldCount) {
      fail(vpHSlamException::parseError, path, lineNumber,
           "expected 8 numbers 't tx ty tz qx qy qz qw', found " + std::to_string(fields.size()) + " fields");
    }
    double v[kTumFieldCount];
    for (size_t i = 0; i < kTumFieldCount; ++i) {
      if (!trajectory_text::parseDouble(fields[i], v[i])) {
        fail(vpHSlamException::parseError, path, lineNumber,
             "field " + std::to_string(i + 1) + " '" + fields[i] + "' is not a finite number");
      }
    }
    // TUM order is qx qy qz qw; Eigen's constructor takes w first.
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double norm = q.norm();
    if (std::abs(norm - 1.) > kQuaternionNormTolerance) {
      std::ostringstream msg;
      msg << "quaternion (qx qy qz qw) has norm " << norm << ", not 1 (tolerance " << kQuaternionNormTolerance
          << "): wrong column order or corrupt line";
      fail(vpHSlamException::parseError, path, lineNumber, msg.str());
    }
    q.normalize();
    checkIncreasing(poses, v[0], path, lineNumber);
    StampedPose pose;
    pose.timestamp = v[0];
    pose.wtc = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.wRc = q.toRotationMatrix();
    poses.push_back(pose);
  }
  if (file.bad()) {
    fail(vpHSlamException::fileUnreadable, path, lineNumber, "read error");
  }
  return poses;
}

void writeTumTrajectory(const std::string &path, const std::vector<StampedPose> &poses)
{
  std::ofstream file;
  trajectory_text::openForWriting(file, path);
  file << "# timestamp[s] tx ty tz qx qy qz qw (camera-to-world, TUM format)\n";
  std::string line;
  for (const StampedPose &pose : poses) {
    Eigen::Quaterniond q(pose.wRc);
    q.normalize();
    // q and -q are the same rotation; a fixed sign makes files comparable and round trips reproducible.
    if (q.w() < 0.) {
      q.coeffs() = -q.coeffs();
    }
    line.clear();
    trajectory_text::appendNumber(line, pose.timestamp, std::chars_format::fixed, kTimestampDecimals);
    for (int i = 0; i < 3; ++i) {
      line += ' ';
      trajectory_text::appendNumber(line, pose.wtc[i], std::chars_format::general, kTranslationSignificantDigits);
    }
    const double qxyzw[4] = {q.x(), q.y(), q.z(), q.w()};
    for (double c : qxyzw) {
      line += ' ';
      trajectory_text::appendNumber(line, c, std::chars_format::fixed, kQuaternionDecimals);
    }
    line += '\n';
    file << line;
  }
  trajectory_text::flushAndClose(file, path);
}

std::vector<StampedPose> readKittiTrajectory(const std::string &path, const std::string &timesPath, double frameRate)
{
  std::ifstream file = openForReading(path);
  std::vector<StampedPose> poses;
  std::vector<size_t> poseLines;
  std::string raw;
  size_t lineNumber = 0;
  while (std::getline(file, raw)) {
    ++lineNumber;
    const std::string line = trajectory_text::stripComment(raw);
    if (line.empty()) {
      continue;
    }
    const std::vector<std::string> fields = trajectory_text::splitFields(line, " \t,");
    if (fields.size() != kKittiFieldCount) {
      fail(vpHSlamException::parseError, path, lineNumber,
           "expected 12 numbers (3x4 matrix, row by row), found " + std::to_string(fields.size()) + " fields");
    }
    double v[kKittiFieldCount];
    for (size_t i = 0; i < kKittiFieldCount; ++i) {
      if (!trajectory_text::parseDouble(fields[i], v[i])) {
        fail(vpHSlamException::parseError, path, lineNumber,
             "field " + std::to_string(i + 1) + " '" + fields[i] + "' is not a finite number");
      }
    }
    StampedPose pose;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        pose.wRc(r, c) = v[4 * r + c];
      }
      pose.wtc[r] = v[4 * r + 3];
    }
    const double orthoError = (pose.wRc.transpose() * pose.wRc - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (orthoError > kRotationOrthonormalityTolerance || pose.wRc.determinant() < 0.) {
      std::ostringstream msg;
      msg << "the left 3x3 block is not a rotation (max|R^T R - I| = " << orthoError
          << ", det = " << pose.wRc.determinant() << ")";
      fail(vpHSlamException::parseError, path, lineNumber, msg.str());
    }
    pose.timestamp = frameRate > 0. ? static_cast<double>(poses.size()) / frameRate : static_cast<double>(poses.size());
    poses.push_back(pose);
    poseLines.push_back(lineNumber);
  }
  if (file.bad()) {
    fail(vpHSlamException::fileUnreadable, path, lineNumber, "read error");
  }
  if (timesPath.empty()) {
    return poses;
  }

  std::ifstream times = openForReading(timesPath);
  size_t count = 0;
  lineNumber = 0;
  while (std::getline(times, raw)) {
    ++lineNumber;
    const std::string line = trajectory_text::stripComment(raw);
    if (line.empty()) {
      continue;
    }
    double t = 0.;
    if (!trajectory_text::parseDouble(line, t)) {
      fail(vpHSlamException::parseError, timesPath, lineNumber, "'" + line + "' is not a time in seconds");
    }
    if (count >= poses.size()) {
      fail(vpHSlamException::invalidTimestamps, timesPath, lineNumber,
           "more times than poses (" + std::to_string(poses.size()) + " poses in " + path + ")");
    }
    if (count > 0 && !(t > poses[count - 1].timestamp)) {
      fail(vpHSlamException::invalidTimestamps, timesPath, lineNumber, "time does not increase");
    }
    poses[count++].timestamp = t;
  }
  if (count != poses.size()) {
    fail(vpHSlamException::invalidTimestamps, timesPath, 0,
         std::to_string(count) + " times for " + std::to_string(poses.size()) + " poses in " + path);
  }
  return poses;
}

void writeKittiTrajectory(const std::string &path, const std::vector<StampedPose> &poses)
{
  std::ofstream file;
  trajectory_text::openForWriting(file, path);
  std::string line;
  for (const StampedPose &pose : poses) {
    line.clear();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        if (r + c > 0) {
          line += ' ';
        }
        const double value = c < 3 ? pose.wRc(r, c) : pose.wtc[r];
        trajectory_text::appendNumber(line, value, std::chars_format::scientific, kKittiDecimals);
      }
    }
    line += '\n';
    file << line;
  }
  trajectory_text::flushAndClose(file, path);
}

void applyBodyToSensor(std::vector<StampedPose> &poses, const Eigen::Matrix4d &bMs)
{
  const Eigen::Matrix3d bRs = bMs.topLeftCorner<3, 3>();
  const Eigen::Vector3d bts = bMs.topRightCorner<3, 1>();
  for (StampedPose &pose : poses) {
    // wMs = wMb * bMs: rotation wRb bRs, origin wRb bts + wtb.
    pose.wtc = pose.wRc * bts + pose.wtc;
    pose.wRc = pose.wRc * bRs;
  }
}

} // namespace hslam
