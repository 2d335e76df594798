#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include "io/TrajectoryConversion.h"
#include "io/TrajectoryIo.h"

#include <algorithm>
#include <numeric>
#include <string>

vpHSlamTrajectory::vpHSlamTrajectory() = default;

void vpHSlamTrajectory::add(double timestamp, const vpHomogeneousMatrix &wMc)
{
  m_timestamps.push_back(timestamp);
  m_wMc.push_back(wMc);
}

void vpHSlamTrajectory::clear()
{
  m_timestamps.clear();
  m_wMc.clear();
}

bool vpHSlamTrajectory::isSorted() const
{
  for (size_t i = 1; i < m_timestamps.size(); ++i) {
    if (!(m_timestamps[i] > m_timestamps[i - 1])) {
      return false;
    }
  }
  return true;
}

void vpHSlamTrajectory::sortByTimestamp()
{
  std::vector<size_t> order(m_timestamps.size());
  std::iota(order.begin(), order.end(), size_t(0));
  std::stable_sort(order.begin(), order.end(),
                   [this](size_t a, size_t b) { return m_timestamps[a] < m_timestamps[b]; });
  std::vector<double> timestamps;
  std::vector<vpHomogeneousMatrix> poses;
  timestamps.reserve(order.size());
  poses.reserve(order.size());
  for (size_t i : order) {
    timestamps.push_back(m_timestamps[i]);
    poses.push_back(m_wMc[i]);
  }
  m_timestamps.swap(timestamps);
  m_wMc.swap(poses);
}

void vpHSlamTrajectory::transformRight(const vpHomogeneousMatrix &cMs)
{
  for (vpHomogeneousMatrix &wMc : m_wMc) {
    wMc = wMc * cMs;
  }
}

void vpHSlamTrajectory::transformLeft(const vpHomogeneousMatrix &aMw)
{
  for (vpHomogeneousMatrix &wMc : m_wMc) {
    wMc = aMw * wMc;
  }
}

vpHSlamTrajectory vpHSlamTrajectory::timeSpan(double from, double to) const
{
  if (!(from <= to)) { // also refuses NaN
    throw vpHSlamException(vpHSlamException::invalidArgument, "trajectory time span: start " + std::to_string(from) +
                                                                  " s is not before end " + std::to_string(to) + " s");
  }
  vpHSlamTrajectory span;
  for (size_t i = 0; i < m_timestamps.size(); ++i) {
    if (m_timestamps[i] >= from && m_timestamps[i] <= to) {
      span.add(m_timestamps[i], m_wMc[i]);
    }
  }
  return span;
}

vpHSlamTrajectory vpHSlamTrajectory::readTum(const std::string &path)
{
  return hslam::toTrajectory(hslam::readTumTrajectory(path));
}

vpHSlamTrajectory vpHSlamTrajectory::readKitti(const std::string &path, const std::string &timesPath, double frameRate)
{
  return hslam::toTrajectory(hslam::readKittiTrajectory(path, timesPath, frameRate));
}

vpHSlamTrajectory vpHSlamTrajectory::readEurocGroundTruth(const std::string &csvPath)
{
  return hslam::toTrajectory(hslam::readEurocGroundTruth(csvPath));
}

vpHSlamTrajectory vpHSlamTrajectory::readEurocGroundTruth(const std::string &csvPath, const std::string &sensorYamlPath)
{
  // Read T_BS first: a missing sensor.yaml is reported before parsing a large csv.
  const Eigen::Matrix4d bMc = hslam::readEurocSensorExtrinsics(sensorYamlPath);
  std::vector<hslam::StampedPose> poses = hslam::readEurocGroundTruth(csvPath);
  hslam::applyBodyToSensor(poses, bMc);
  return hslam::toTrajectory(poses);
}

vpHomogeneousMatrix vpHSlamTrajectory::readEurocSensorExtrinsics(const std::string &sensorYamlPath)
{
  const Eigen::Matrix4d bMc = hslam::readEurocSensorExtrinsics(sensorYamlPath);
  hslam::StampedPose pose;
  pose.wRc = bMc.topLeftCorner<3, 3>();
  pose.wtc = bMc.topRightCorner<3, 1>();
  return hslam::toHomogeneousMatrix(pose);
}

vpHSlamTrajectory vpHSlamTrajectory::load(const std::string &path, Format format)
{
  switch (format) {
  case formatTum:
    return readTum(path);
  case formatKitti:
    return readKitti(path);
  case formatEuroc:
    return readEurocGroundTruth(path);
  }
  throw vpHSlamException(vpHSlamException::invalidArgument, path + ": unknown trajectory format");
}

vpHSlamTrajectory::Format vpHSlamTrajectory::formatFromString(const std::string &name)
{
  if (name == "tum") {
    return formatTum;
  }
  if (name == "kitti") {
    return formatKitti;
  }
  if (name == "euroc") {
    return formatEuroc;
  }
  throw vpHSlamException(vpHSlamException::invalidArgument,
                         "unknown trajectory format '" + name + "' (expected tum, kitti or euroc)");
}

void vpHSlamTrajectory::saveTum(const std::string &path) const
{
  hslam::writeTumTrajectory(path, hslam::toStampedPoses(*this));
}

void vpHSlamTrajectory::saveKitti(const std::string &path) const
{
  hslam::writeKittiTrajectory(path, hslam::toStampedPoses(*this));
}

void vpHSlamTrajectory::save(const std::string &path, Format format) const
{
  switch (format) {
  case formatTum:
    saveTum(path);
    return;
  case formatKitti:
    saveKitti(path);
    return;
  case formatEuroc:
    break;
  }
  throw vpHSlamException(vpHSlamException::unsupported, path + ": writing the EuRoC format is not supported");
}
