// TUM and KITTI trajectory formats. EuRoC lives in TrajectoryEuroc.cpp.
#include "io/TrajectoryIo.h"
#include "common/TextParsing.h"

#include <Eigen/Geometry>
#include <Eigen/LU>

#include <fstream>
#include <sstream>

namespace hslam
{
namespace
{
//! TUM: t tx ty tz qx qy qz qw.
constexpr size_t kTumFieldCount = 8;
//! KITTI: 3x4 matrix row by row.
constexpr size_t kKittiFieldCount = 12;
//! Printed precision of the writers (see writeTumTrajectory's documentation).
constexpr int kTimestampDecimals = 9;
constexpr int kTranslationSignificantDigits = 10;
constexpr int kQuaternionDecimals = 9;
constexpr int kKittiDecimals = 9;
//! Field separators the readers accept: blanks and commas, repeated or mixed.
const char *const kFieldSeparators = " \t,";

//! The \e count numbers of one data line, \e layout naming them for the message when the count differs.
std::vector<double> readNumberRow(const TextLine &line, size_t count, const std::string &layout,
                                  const std::string &path)
{
  const std::vector<std::string> fields = splitTokens(line.text, kFieldSeparators);
  expectTokenCount(fields, count, path, line.number, layout);
  std::vector<double> values(count);
  for (size_t i = 0; i < count; ++i) {
    values[i] = parseDouble(fields[i], path, line.number, "field " + std::to_string(i + 1));
  }
  return values;
}
} // namespace

Eigen::Matrix3d rotationFromFileQuaternion(double w, double x, double y, double z, const std::string &columns,
                                           const std::string &path, size_t line)
{
  Eigen::Quaterniond q(w, x, y, z);
  const double norm = q.norm();
  if (std::abs(norm - 1.) > kQuaternionNormTolerance) {
    std::ostringstream msg;
    msg << "quaternion (" << columns << ") has norm " << norm << ", not 1 (tolerance " << kQuaternionNormTolerance
        << "): wrong column order or corrupt line";
    throwAt(vpHSlamException::parseError, path, line, msg.str());
  }
  q.normalize();
  return q.toRotationMatrix();
}

std::string rotationDefect(const Eigen::Matrix3d &R)
{
  const double orthoError = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  if (orthoError <= kRotationOrthonormalityTolerance && det >= 0.) {
    return std::string();
  }
  std::ostringstream msg;
  msg << "max|R^T R - I| = " << orthoError << ", det = " << det;
  return msg.str();
}

void checkIncreasing(const std::vector<StampedPose> &poses, double timestamp, const std::string &path, size_t line)
{
  if (!poses.empty() && !(timestamp > poses.back().timestamp)) {
    std::ostringstream msg;
    msg.precision(17);
    msg << "timestamp " << timestamp << " does not increase (previous " << poses.back().timestamp << ")";
    throwAt(vpHSlamException::invalidTimestamps, path, line, msg.str());
  }
}

std::vector<StampedPose> readTumTrajectory(const std::string &path)
{
  std::vector<StampedPose> poses;
  for (const TextLine &line : readDataLines(path, "trajectory file")) {
    const std::vector<double> v = readNumberRow(line, kTumFieldCount, "'t tx ty tz qx qy qz qw'", path);
    // TUM order is qx qy qz qw.
    const Eigen::Matrix3d wRc = rotationFromFileQuaternion(v[7], v[4], v[5], v[6], "qx qy qz qw", path, line.number);
    checkIncreasing(poses, v[0], path, line.number);
    StampedPose pose;
    pose.timestamp = v[0];
    pose.wtc = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.wRc = wRc;
    poses.push_back(pose);
  }
  return poses;
}

void writeTumTrajectory(const std::string &path, const std::vector<StampedPose> &poses)
{
  std::ofstream file;
  openForWriting(file, path);
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
    appendNumber(line, pose.timestamp, std::chars_format::fixed, kTimestampDecimals);
    for (int i = 0; i < 3; ++i) {
      line += ' ';
      appendNumber(line, pose.wtc[i], std::chars_format::general, kTranslationSignificantDigits);
    }
    const double qxyzw[4] = {q.x(), q.y(), q.z(), q.w()};
    for (double c : qxyzw) {
      line += ' ';
      appendNumber(line, c, std::chars_format::fixed, kQuaternionDecimals);
    }
    line += '\n';
    file << line;
  }
  flushAndClose(file, path);
}

std::vector<StampedPose> readKittiTrajectory(const std::string &path, const std::string &timesPath, double frameRate)
{
  std::vector<StampedPose> poses;
  for (const TextLine &line : readDataLines(path, "trajectory file")) {
    const std::vector<double> v = readNumberRow(line, kKittiFieldCount, "a 3x4 matrix, row by row", path);
    StampedPose pose;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        pose.wRc(r, c) = v[4 * r + c];
      }
      pose.wtc[r] = v[4 * r + 3];
    }
    const std::string defect = rotationDefect(pose.wRc);
    if (!defect.empty()) {
      throwAt(vpHSlamException::parseError, path, line.number, "the left 3x3 block is not a rotation (" + defect + ")");
    }
    pose.timestamp = frameRate > 0. ? static_cast<double>(poses.size()) / frameRate : static_cast<double>(poses.size());
    poses.push_back(pose);
  }
  if (timesPath.empty()) {
    return poses;
  }

  size_t count = 0;
  for (const TextLine &line : readDataLines(timesPath, "KITTI times file")) {
    const double t = parseDouble(line.text, timesPath, line.number, "time in seconds");
    if (count >= poses.size()) {
      throwAt(vpHSlamException::invalidTimestamps, timesPath, line.number,
              "more times than poses (" + std::to_string(poses.size()) + " poses in " + path + ")");
    }
    if (count > 0 && !(t > poses[count - 1].timestamp)) {
      throwAt(vpHSlamException::invalidTimestamps, timesPath, line.number, "time does not increase");
    }
    poses[count++].timestamp = t;
  }
  if (count != poses.size()) {
    throwAt(vpHSlamException::invalidTimestamps, timesPath, 0,
            std::to_string(count) + " times for " + std::to_string(poses.size()) + " poses in " + path);
  }
  return poses;
}

void writeKittiTrajectory(const std::string &path, const std::vector<StampedPose> &poses)
{
  std::ofstream file;
  openForWriting(file, path);
  std::string line;
  for (const StampedPose &pose : poses) {
    line.clear();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        if (r + c > 0) {
          line += ' ';
        }
        const double value = c < 3 ? pose.wRc(r, c) : pose.wtc[r];
        appendNumber(line, value, std::chars_format::scientific, kKittiDecimals);
      }
    }
    line += '\n';
    file << line;
  }
  flushAndClose(file, path);
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
