// EuRoC ASL ground truth (state_groundtruth_estimate0/data.csv) and sensor extrinsics (sensor.yaml, T_BS).
#include "io/TrajectoryIo.h"
#include "io/TrajectoryText.h"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <opencv2/core.hpp>

#include <fstream>
#include <sstream>

namespace hslam
{
namespace
{
using trajectory_text::fail;

//! timestamp[ns], p (3), q (w x y z): the columns we use; velocities and biases may follow.
constexpr size_t kEurocMinFieldCount = 8;
constexpr double kNanosecondsPerSecond = 1e9;
constexpr int kTransformSize = 4;
} // namespace

std::vector<StampedPose> readEurocGroundTruth(const std::string &csvPath)
{
  std::ifstream file(csvPath);
  if (!file.is_open()) {
    fail(vpHSlamException::fileNotFound, csvPath, 0, "cannot open the EuRoC ground-truth csv (missing or unreadable)");
  }
  std::vector<StampedPose> poses;
  std::string raw;
  size_t lineNumber = 0;
  while (std::getline(file, raw)) {
    ++lineNumber;
    // The header starts with '#timestamp': stripComment removes it like any comment.
    const std::string line = trajectory_text::stripComment(raw);
    if (line.empty()) {
      continue;
    }
    const std::vector<std::string> fields = trajectory_text::splitFields(line, ", \t");
    if (fields.size() < kEurocMinFieldCount) {
      fail(vpHSlamException::parseError, csvPath, lineNumber,
           "expected at least 8 comma-separated values (timestamp[ns], p x y z, q w x y z), found " +
               std::to_string(fields.size()));
    }
    // Nanoseconds are integers of 19 digits: parse them as integers, a double would round them first.
    long long ns = 0;
    double t = 0.;
    if (trajectory_text::parseInt64(fields[0], ns)) {
      t = static_cast<double>(ns / 1000000000LL) + static_cast<double>(ns % 1000000000LL) / kNanosecondsPerSecond;
    } else if (trajectory_text::parseDouble(fields[0], t)) {
      t /= kNanosecondsPerSecond;
    } else {
      fail(vpHSlamException::parseError, csvPath, lineNumber, "timestamp '" + fields[0] + "' is not a number of ns");
    }
    double v[kEurocMinFieldCount - 1];
    for (size_t i = 1; i < kEurocMinFieldCount; ++i) {
      if (!trajectory_text::parseDouble(fields[i], v[i - 1])) {
        fail(vpHSlamException::parseError, csvPath, lineNumber,
             "field " + std::to_string(i + 1) + " '" + fields[i] + "' is not a finite number");
      }
    }
    Eigen::Quaterniond q(v[3], v[4], v[5], v[6]); // EuRoC: q_RS_w, q_RS_x, q_RS_y, q_RS_z
    const double norm = q.norm();
    if (std::abs(norm - 1.) > kQuaternionNormTolerance) {
      std::ostringstream msg;
      msg << "quaternion (w x y z) has norm " << norm << ", not 1 (tolerance " << kQuaternionNormTolerance << ")";
      fail(vpHSlamException::parseError, csvPath, lineNumber, msg.str());
    }
    if (!poses.empty() && !(t > poses.back().timestamp)) {
      fail(vpHSlamException::invalidTimestamps, csvPath, lineNumber, "timestamp does not increase");
    }
    q.normalize();
    StampedPose pose;
    pose.timestamp = t;
    pose.wtc = Eigen::Vector3d(v[0], v[1], v[2]);
    pose.wRc = q.toRotationMatrix();
    poses.push_back(pose);
  }
  if (file.bad()) {
    fail(vpHSlamException::fileUnreadable, csvPath, lineNumber, "read error");
  }
  return poses;
}

Eigen::Matrix4d readEurocSensorExtrinsics(const std::string &sensorYamlPath)
{
  {
    std::ifstream probe(sensorYamlPath);
    if (!probe.is_open()) {
      fail(vpHSlamException::fileNotFound, sensorYamlPath, 0, "cannot open the EuRoC sensor.yaml");
    }
  }
  std::vector<double> data;
  try {
    cv::FileStorage fs(sensorYamlPath, cv::FileStorage::READ);
    if (!fs.isOpened()) {
      fail(vpHSlamException::parseError, sensorYamlPath, 0, "not a YAML file OpenCV can read (needs '%YAML:1.0')");
    }
    const cv::FileNode node = fs["T_BS"];
    if (node.empty()) {
      fail(vpHSlamException::parseError, sensorYamlPath, 0, "no T_BS entry");
    }
    const cv::FileNode dataNode = node["data"];
    if (dataNode.empty() || !dataNode.isSeq()) {
      fail(vpHSlamException::parseError, sensorYamlPath, 0, "T_BS has no 'data' list");
    }
    for (cv::FileNodeIterator it = dataNode.begin(); it != dataNode.end(); ++it) {
      data.push_back(static_cast<double>(*it));
    }
  } catch (const cv::Exception &e) {
    fail(vpHSlamException::parseError, sensorYamlPath, 0, std::string("YAML parse error: ") + e.what());
  }
  if (data.size() != static_cast<size_t>(kTransformSize * kTransformSize)) {
    fail(vpHSlamException::parseError, sensorYamlPath, 0,
         "T_BS data has " + std::to_string(data.size()) + " values, expected 16 (4x4 row-major)");
  }
  Eigen::Matrix4d bMs;
  for (int r = 0; r < kTransformSize; ++r) {
    for (int c = 0; c < kTransformSize; ++c) {
      bMs(r, c) = data[kTransformSize * r + c];
    }
  }
  const Eigen::Matrix3d bRs = bMs.topLeftCorner<3, 3>();
  const double orthoError = (bRs.transpose() * bRs - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (orthoError > kRotationOrthonormalityTolerance || bRs.determinant() < 0.) {
    fail(vpHSlamException::invalidCalibration, sensorYamlPath, 0, "T_BS rotation block is not a rotation");
  }
  return bMs;
}

} // namespace hslam
