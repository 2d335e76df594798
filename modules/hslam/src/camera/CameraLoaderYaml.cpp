/*
 * H-SLAM for ViSP.
 */
// vpHSlamCamera::loadEurocYaml(): EuRoC / TUM-VI sensor.yaml and Kalibr camchain (first "camN" entry) through
// cv::FileStorage. camera_model must be pinhole; distortion_model radial-tangential | radtan | equidistant | equi |
// fov | none (absent = none); coefficients under distortion_coefficients (EuRoC) or distortion_coeffs (Kalibr).
// cv::FileStorage requires OpenCV's "%YAML:1.0" first line, which Kalibr files lack: it is supplied in memory.
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>

#include "camera/CameraLoaderSupport.h"
#include "common/TextParsing.h"

#include <opencv2/core.hpp>

#include <cmath>
#include <limits>

namespace
{
using hslam::kIntrinsicCount;
using hslam::kSizeCount;
using hslam::makeCamera;
using hslam::setDefaultRectification;

std::vector<double> yamlNumbers(const cv::FileNode &node, const std::string &path, const std::string &key)
{
  std::vector<double> values;
  if (node.empty() || node.isNone()) {
    return values;
  }
  if (!node.isSeq()) {
    throw vpHSlamException(vpHSlamException::parseError, path + ": field '" + key + "' must be a list of numbers");
  }
  for (cv::FileNodeIterator it = node.begin(); it != node.end(); ++it) {
    if (!(*it).isReal() && !(*it).isInt()) {
      throw vpHSlamException(vpHSlamException::parseError,
                             path + ": field '" + key + "' holds a value that is not a number");
    }
    values.push_back(static_cast<double>(*it));
  }
  return values;
}

std::string yamlString(const cv::FileNode &node, const std::string &path, const std::string &key)
{
  if (node.empty() || node.isNone()) {
    return std::string();
  }
  if (!node.isString()) {
    throw vpHSlamException(vpHSlamException::parseError, path + ": field '" + key + "' must be a string");
  }
  return static_cast<std::string>(node);
}

void requireCount(const std::vector<double> &values, std::size_t expected, const std::string &path,
                  const std::string &key)
{
  if (values.size() != expected) {
    throw vpHSlamException(vpHSlamException::parseError, path + ": field '" + key + "' must hold " +
                                                             std::to_string(expected) + " numbers, found " +
                                                             std::to_string(values.size()));
  }
}

vpHSlamCamera readYamlCamera(const cv::FileNode &cam, const std::string &path)
{
  const std::string cameraModel = hslam::toLower(yamlString(cam["camera_model"], path, "camera_model"));
  if (cameraModel != "pinhole") {
    throw vpHSlamException(vpHSlamException::unsupported,
                           path + ": camera_model '" + cameraModel +
                               "' is not supported (pinhole with radtan, equidistant or fov distortion only)");
  }
  const std::vector<double> intrinsics = yamlNumbers(cam["intrinsics"], path, "intrinsics");
  requireCount(intrinsics, kIntrinsicCount, path, "intrinsics");
  const std::vector<double> resolution = yamlNumbers(cam["resolution"], path, "resolution");
  requireCount(resolution, kSizeCount, path, "resolution");
  for (double r : resolution) {
    if (!(r >= 1.0) || r != std::floor(r) || r > std::numeric_limits<unsigned int>::max()) {
      throw vpHSlamException(vpHSlamException::invalidCalibration, path + ": resolution must be two positive integers");
    }
  }

  // EuRoC writes distortion_coefficients, Kalibr distortion_coeffs.
  const char *coeffKey = cam["distortion_coefficients"].empty() ? "distortion_coeffs" : "distortion_coefficients";
  const std::vector<double> coefficients = yamlNumbers(cam[coeffKey], path, coeffKey);
  const std::string distortionModel = hslam::toLower(yamlString(cam["distortion_model"], path, "distortion_model"));

  vpHSlamCamera::Model model;
  if (distortionModel == "radial-tangential" || distortionModel == "radtan") {
    model = vpHSlamCamera::radialTangential;
  } else if (distortionModel == "equidistant" || distortionModel == "equi") {
    model = vpHSlamCamera::equidistant;
  } else if (distortionModel == "fov") {
    model = vpHSlamCamera::fov;
  } else if (distortionModel == "none" || distortionModel.empty()) {
    model = vpHSlamCamera::pinhole;
    for (double c : coefficients) {
      if (c != 0.0) {
        throw vpHSlamException(vpHSlamException::invalidCalibration,
                               path + ": distortion_model none with non-zero distortion coefficients");
      }
    }
  } else {
    throw vpHSlamException(vpHSlamException::unsupported,
                           path + ": distortion_model '" + distortionModel +
                               "' is not supported (radial-tangential, radtan, equidistant, equi, fov, none)");
  }
  const std::vector<double> distortion = model == vpHSlamCamera::pinhole ? std::vector<double>() : coefficients;
  vpHSlamCamera camera =
      makeCamera(path, model, static_cast<unsigned int>(resolution[0]), static_cast<unsigned int>(resolution[1]),
                 intrinsics[0], intrinsics[1], intrinsics[2], intrinsics[3], distortion);
  setDefaultRectification(camera, path);
  return camera;
}

// The file's text with OpenCV's "%YAML:1.0" directive first: cv::FileStorage rejects YAML without it (Kalibr) or with
// the standard "%YAML 1.x" spelling.
std::string withOpenCVDirective(const std::string &path)
{
  std::string text = hslam::readTextFile(path, "camera YAML");
  hslam::requireNoNulByte(text, path);
  hslam::requireYamlLineShapes(text, path); // before OpenCV's reader, which can hang on other lines
  const std::string directive = "%YAML:1.0";
  if (hslam::startsWith(text, "%YAML:")) {
    return text;
  }
  if (hslam::startsWith(text, "%YAML")) {
    const std::size_t eol = text.find('\n');
    text = eol == std::string::npos ? std::string() : text.substr(eol + 1);
  }
  return directive + "\n" + text;
}
} // namespace

vpHSlamCamera vpHSlamCamera::loadEurocYaml(const std::string &path)
{
  hslam::requireFileExists(path, "camera YAML");
  try {
    const std::string text = withOpenCVDirective(path);
    cv::FileStorage fs(text, cv::FileStorage::READ | cv::FileStorage::MEMORY | cv::FileStorage::FORMAT_YAML);
    if (!fs.isOpened()) {
      throw vpHSlamException(vpHSlamException::fileUnreadable, path + ": cannot be opened as YAML");
    }
    const cv::FileNode root = fs.root();
    if (!root.isMap()) {
      throw vpHSlamException(vpHSlamException::parseError, path + ": expected a YAML map at top level");
    }
    if (!root["camera_model"].empty()) {
      return readYamlCamera(root, path); // EuRoC / TUM-VI sensor.yaml
    }
    for (cv::FileNodeIterator it = root.begin(); it != root.end(); ++it) {
      const cv::FileNode node = *it;
      if (hslam::startsWith(node.name(), "cam") && node.isMap() && !node["camera_model"].empty()) {
        return readYamlCamera(node, path); // Kalibr camchain: first camera
      }
    }
    throw vpHSlamException(vpHSlamException::parseError,
                           path + ": no camera_model field (neither an EuRoC sensor.yaml nor a Kalibr camchain)");
  } catch (const cv::Exception &e) {
    throw vpHSlamException(vpHSlamException::parseError, path + ": invalid YAML: " + e.msg);
  } catch (const vpException &) {
    throw; // ours, already naming the file
  } catch (const std::exception &e) {
    // OpenCV's YAML reader lets standard exceptions out on some malformed input (std::length_error; found by
    // fuzz_camera_yaml).
    throw vpHSlamException(vpHSlamException::parseError, path + ": invalid YAML (" + e.what() + ")");
  }
}
