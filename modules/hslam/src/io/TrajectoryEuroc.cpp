// EuRoC ASL ground truth (state_groundtruth_estimate0/data.csv) and sensor extrinsics (sensor.yaml, T_BS).
#include "common/TextParsing.h"
#include "io/TrajectoryIo.h"

#include <opencv2/core.hpp>

namespace hslam
{
namespace
{
//! timestamp[ns], p (3), q (w x y z): the columns we use; velocities and biases may follow.
constexpr size_t kEurocMinFieldCount = 8;
constexpr double kNanosecondsPerSecond = 1e9;
constexpr int kTransformSize = 4;
} // namespace

std::vector<StampedPose> readEurocGroundTruth(const std::string &csvPath)
{
  std::vector<StampedPose> poses;
  // The header starts with '#timestamp': readDataLines drops it like any comment.
  for (const TextLine &line : readDataLines(csvPath, "EuRoC ground-truth csv")) {
    const std::vector<std::string> fields = splitTokens(line.text, ", \t");
    if (fields.size() < kEurocMinFieldCount) {
      throwAt(vpHSlamException::parseError, csvPath, line.number,
              "expected at least 8 comma-separated values (timestamp[ns], p x y z, q w x y z), found " +
                  std::to_string(fields.size()));
    }
    // Nanoseconds are integers of 19 digits: parse them as integers, a double would round them first.
    long long ns = 0;
    double t = 0.;
    if (tryParseInt64(fields[0], ns)) {
      t = static_cast<double>(ns / 1000000000LL) + static_cast<double>(ns % 1000000000LL) / kNanosecondsPerSecond;
    } else if (tryParseDouble(fields[0], t)) {
      t /= kNanosecondsPerSecond;
    } else {
      throwAt(vpHSlamException::parseError, csvPath, line.number,
              "timestamp '" + fields[0] + "' is not a number of ns");
    }
    // Velocities and biases may follow: only the pose columns are parsed.
    double v[kEurocMinFieldCount - 1];
    for (size_t i = 1; i < kEurocMinFieldCount; ++i) {
      v[i - 1] = parseDouble(fields[i], csvPath, line.number, "field " + std::to_string(i + 1));
    }
    // EuRoC: q_RS_w, q_RS_x, q_RS_y, q_RS_z.
    const Eigen::Matrix3d wRc = rotationFromFileQuaternion(v[3], v[4], v[5], v[6], "w x y z", csvPath, line.number);
    checkIncreasing(poses, t, csvPath, line.number);
    StampedPose pose;
    pose.timestamp = t;
    pose.wtc = Eigen::Vector3d(v[0], v[1], v[2]);
    pose.wRc = wRc;
    poses.push_back(pose);
  }
  return poses;
}

Eigen::Matrix4d readEurocSensorExtrinsics(const std::string &sensorYamlPath)
{
  requireFileExists(sensorYamlPath, "EuRoC sensor.yaml");
  const std::string text = readTextFile(sensorYamlPath, "EuRoC sensor.yaml");
  requireNoNulByte(text, sensorYamlPath);
  requireYamlLineShapes(text, sensorYamlPath); // before OpenCV's reader, which can hang on other lines
  std::vector<double> data;
  try {
    cv::FileStorage fs(sensorYamlPath, cv::FileStorage::READ);
    if (!fs.isOpened()) {
      throwAt(vpHSlamException::parseError, sensorYamlPath, 0, "not a YAML file OpenCV can read (needs '%YAML:1.0')");
    }
    const cv::FileNode node = fs["T_BS"];
    if (node.empty()) {
      throwAt(vpHSlamException::parseError, sensorYamlPath, 0, "no T_BS entry");
    }
    const cv::FileNode dataNode = node["data"];
    if (dataNode.empty() || !dataNode.isSeq()) {
      throwAt(vpHSlamException::parseError, sensorYamlPath, 0, "T_BS has no 'data' list");
    }
    for (cv::FileNodeIterator it = dataNode.begin(); it != dataNode.end(); ++it) {
      data.push_back(static_cast<double>(*it));
    }
  } catch (const cv::Exception &e) {
    throwAt(vpHSlamException::parseError, sensorYamlPath, 0, std::string("YAML parse error: ") + e.what());
  } catch (const vpException &) {
    throw; // ours, already naming the file
  } catch (const std::exception &e) {
    // OpenCV's YAML reader lets standard exceptions out on some malformed input (std::length_error).
    throwAt(vpHSlamException::parseError, sensorYamlPath, 0, std::string("YAML parse error (") + e.what() + ")");
  }
  if (data.size() != static_cast<size_t>(kTransformSize * kTransformSize)) {
    throwAt(vpHSlamException::parseError, sensorYamlPath, 0,
            "T_BS data has " + std::to_string(data.size()) + " values, expected 16 (4x4 row-major)");
  }
  Eigen::Matrix4d bMs;
  for (int r = 0; r < kTransformSize; ++r) {
    for (int c = 0; c < kTransformSize; ++c) {
      bMs(r, c) = data[kTransformSize * r + c];
    }
  }
  const std::string defect = rotationDefect(bMs.topLeftCorner<3, 3>());
  if (!defect.empty()) {
    throwAt(vpHSlamException::invalidCalibration, sensorYamlPath, 0,
            "T_BS rotation block is not a rotation (" + defect + ")");
  }
  return bMs;
}

} // namespace hslam
