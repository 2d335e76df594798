/*
 * H-SLAM for ViSP.
 */
// Calibration file readers of vpHSlamCamera, plain-text part: DSO camera.txt, KITTI odometry calib.txt and the
// load() dispatcher (ViSP XML and YAML readers are in CameraLoaderViSPXml.cpp and CameraLoaderYaml.cpp). Every
// failure is a vpHSlamException whose message starts with the file (and line) at fault.
//
// DSO camera.txt follows DSO's src/util/Undistort.cpp: model keyword line, input size line, optional rectification
// line ("crop" | "full" | "none" | "fx fy cx cy 0") and output size line. Intrinsics with cx < 1 and cy < 1 are
// relative and become fx*w, fy*h, cx*w - 0.5, cy*h - 0.5 (DSO: the relative format puts the centre of pixel (0,0) at
// (0.5,0.5), ours at (0,0)). The same rule applies to an explicit rectification line, scaled by the output size
// (DSO always reads that line as relative; pixels are accepted here when cx or cy >= 1). The keyword-less legacy
// forms are read too: 5 numbers = ATAN/FOV (omega 0 = pinhole), 8 numbers = RadTan. Missing lines 3-4 mean crop
// (distorted models) or none (pinhole) at the input size; a missing line 4 means the input size. "EquiDistant" and
// "KannalaBrandt" are the same polynomial theta (1 + k1 theta^2 + ...) in DSO and both map to equidistant.
// Stricter than DSO: extra tokens on a line, and a non-zero fifth value after "Pinhole" or in an explicit
// rectification line, are errors instead of being ignored. Lines after the fourth are ignored.
//
// KITTI: only the left 3x3 block of the projection matrix is used; the image size is not in the file.
#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>

#include "camera/CameraLoaderSupport.h"
#include "common/TextParsing.h"

#include <cmath>
#include <string>

namespace
{
using hslam::applyRectification;
using hslam::fileLine;
using hslam::kIntrinsicCount;
using hslam::kSizeCount;
using hslam::makeCamera;
using hslam::setDefaultRectification;

// DSO (Undistort.cpp): intrinsics whose principal point is below 1 are relative to the image size.
constexpr double kRelativeIntrinsicsLimit = 1.0;
// DSO: shift from the relative format's pixel-corner origin to a pixel-centre origin, in pixels.
constexpr double kDsoPixelCentreShift = 0.5;
// KITTI projection matrices have an exact [0 0 1] third row and zero skew; anything else is not a KITTI file.
constexpr double kProjectionTolerance = 1e-9;

// Line numbers of DSO camera.txt fields.
constexpr std::size_t kDsoModelLine = 1;
constexpr std::size_t kDsoInputSizeLine = 2;
constexpr std::size_t kDsoRectificationLine = 3;
constexpr std::size_t kDsoOutputSizeLine = 4;

// Token counts.
constexpr std::size_t kExplicitRectTokens = 5;    // fx fy cx cy 0
constexpr std::size_t kLegacyAtanTokens = 5;      // fx fy cx cy omega
constexpr std::size_t kLegacyRadTanTokens = 8;    // fx fy cx cy k1 k2 p1 p2
constexpr std::size_t kKittiProjectionCount = 12; // 3x4 row-major

struct DsoModelKeyword {
  const char *keyword;
  vpHSlamCamera::Model model;
  std::size_t parameterCount; // values after fx fy cx cy
};

// DSO's keywords. DSO itself matches "EquiDistant" but builds its reader with "Equidistant": accept both.
const DsoModelKeyword kDsoModels[] = {
    {"Pinhole", vpHSlamCamera::pinhole, 1},           {"RadTan", vpHSlamCamera::radialTangential, 4},
    {"EquiDistant", vpHSlamCamera::equidistant, 4},   {"Equidistant", vpHSlamCamera::equidistant, 4},
    {"KannalaBrandt", vpHSlamCamera::equidistant, 4}, {"FOV", vpHSlamCamera::fov, 1},
};

bool isRelative(double cx, double cy)
{
  return cx < kRelativeIntrinsicsLimit && cy < kRelativeIntrinsicsLimit;
}

// DSO: relative intrinsics to pixels.
void relativeToPixels(unsigned int width, unsigned int height, double &fx, double &fy, double &cx, double &cy)
{
  fx *= width;
  fy *= height;
  cx = cx * width - kDsoPixelCentreShift;
  cy = cy * height - kDsoPixelCentreShift;
}

// A "w h" line: two positive integers.
void parseSizeLine(const hslam::TextLine &line, const std::string &path, const std::string &what, unsigned int &width,
                   unsigned int &height)
{
  const std::vector<std::string> tokens = hslam::splitWhitespace(line.text);
  hslam::expectTokenCount(tokens, kSizeCount, path, line.number, what + " 'width height'");
  width = hslam::parseUnsigned(tokens[0], path, line.number, what + " width");
  height = hslam::parseUnsigned(tokens[1], path, line.number, what + " height");
  if (width == 0 || height == 0) {
    throw vpHSlamException(vpHSlamException::invalidCalibration, fileLine(path, line.number) + ": " + what + " " +
                                                                     std::to_string(width) + "x" +
                                                                     std::to_string(height) + " must be positive");
  }
}
} // namespace

namespace hslam
{
namespace
{
// Rethrow a calibration error with the file (and line) in front, keeping its code.
[[noreturn]] void rethrowWithLocation(const std::string &where, const vpException &e)
{
  const auto *hslamError = dynamic_cast<const vpHSlamException *>(&e);
  const vpHSlamException::ErrorCode code = hslamError ? static_cast<vpHSlamException::ErrorCode>(hslamError->getCode())
                                                      : vpHSlamException::invalidCalibration;
  throw vpHSlamException(code, where + ": " + e.getStringMessage());
}

} // namespace

vpHSlamCamera makeCamera(const std::string &where, vpHSlamCamera::Model model, unsigned int width, unsigned int height,
                         double fx, double fy, double cx, double cy, const std::vector<double> &distortion)
{
  try {
    return vpHSlamCamera(model, width, height, fx, fy, cx, cy, distortion);
  } catch (const vpException &e) {
    rethrowWithLocation(where, e);
  }
}

void applyRectification(vpHSlamCamera &cam, const std::string &where, vpHSlamCamera::RectificationMode mode,
                        unsigned int width, unsigned int height, const vpCameraParameters &K)
{
  try {
    cam.setRectification(mode, width, height, K);
  } catch (const vpException &e) {
    rethrowWithLocation(where, e);
  }
}

// DSO's default when camera.txt stops after the size line: distorted models are cropped, pinhole passes through.
void setDefaultRectification(vpHSlamCamera &cam, const std::string &where)
{
  const vpHSlamCamera::RectificationMode mode =
      cam.getModel() == vpHSlamCamera::pinhole ? vpHSlamCamera::rectifyNone : vpHSlamCamera::rectifyCrop;
  applyRectification(cam, where, mode, cam.getWidth(), cam.getHeight());
}
} // namespace hslam

// ----------------------------------------------------------------------------------------------------------------

namespace
{
// The lines of a DSO camera.txt, trailing empty lines dropped; an empty file or an empty line among the first four is
// an error.
std::vector<hslam::TextLine> readDsoLines(const std::string &path)
{
  std::vector<hslam::TextLine> lines = hslam::readTextLines(path);
  while (!lines.empty() && hslam::trim(lines.back().text).empty()) {
    lines.pop_back();
  }
  if (lines.empty()) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, kDsoModelLine) + ": empty file, expected '<Model> fx fy cx cy <params>'");
  }
  for (const hslam::TextLine &line : lines) {
    if (line.number <= kDsoOutputSizeLine && hslam::trim(line.text).empty()) {
      throw vpHSlamException(vpHSlamException::parseError, fileLine(path, line.number) + ": unexpected empty line");
    }
  }
  return lines;
}

// DSO's keyword-less legacy model line: 5 values (fx fy cx cy omega; omega 0 = pinhole) or 8 (RadTan).
void parseLegacyModelLine(const std::vector<std::string> &tokens, const hslam::TextLine &modelLine,
                          const std::string &path, vpHSlamCamera::Model &model, std::vector<double> &values)
{
  if (tokens.size() != kLegacyAtanTokens && tokens.size() != kLegacyRadTanTokens) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, modelLine.number) +
                               ": expected 5 (fx fy cx cy omega) or 8 (fx fy cx cy k1 k2 p1 p2) values, found " +
                               std::to_string(tokens.size()));
  }
  values = hslam::parseDoubles(tokens, 0, path, modelLine.number, "camera parameters");
  if (tokens.size() == kLegacyRadTanTokens) {
    model = vpHSlamCamera::radialTangential;
  } else if (values[kIntrinsicCount] == 0.0) {
    model = vpHSlamCamera::pinhole; // DSO: omega 0 means no distortion
    values.pop_back();
  } else {
    model = vpHSlamCamera::fov;
  }
}

// A model line that starts with one of DSO's keywords (kDsoModels), then fx fy cx cy and the model's parameters.
void parseKeywordModelLine(const std::vector<std::string> &tokens, const hslam::TextLine &modelLine,
                           const std::string &path, vpHSlamCamera::Model &model, std::vector<double> &values)
{
  const DsoModelKeyword *keyword = nullptr;
  for (const DsoModelKeyword &k : kDsoModels) {
    if (tokens[0] == k.keyword) {
      keyword = &k;
    }
  }
  if (!keyword) {
    throw vpHSlamException(vpHSlamException::unsupported,
                           fileLine(path, modelLine.number) + ": unknown camera model '" + tokens[0] +
                               "' (DSO camera.txt knows Pinhole, RadTan, EquiDistant, KannalaBrandt, FOV)");
  }
  hslam::expectTokenCount(tokens, 1 + kIntrinsicCount + keyword->parameterCount, path, modelLine.number,
                          std::string(keyword->keyword) + " model line (keyword included)");
  values = hslam::parseDoubles(tokens, 1, path, modelLine.number, std::string(keyword->keyword) + " parameter");
  model = keyword->model;
  if (model == vpHSlamCamera::pinhole) {
    if (values.back() != 0.0) {
      throw vpHSlamException(vpHSlamException::invalidCalibration,
                             fileLine(path, modelLine.number) +
                                 ": the fifth value of a Pinhole line must be 0 (use FOV for an ATAN camera)");
    }
    values.pop_back();
  }
}

// An explicit rectification line 'fx fy cx cy 0': the rectified intrinsics, relative ones scaled by the output size.
vpCameraParameters parseExplicitRectification(const std::vector<std::string> &tokens, const hslam::TextLine &rectLine,
                                              const std::string &path, unsigned int outWidth, unsigned int outHeight)
{
  const std::string where = fileLine(path, rectLine.number);
  hslam::expectTokenCount(tokens, kExplicitRectTokens, path, rectLine.number, "rectification 'fx fy cx cy 0'");
  const std::vector<double> rect = hslam::parseDoubles(tokens, 0, path, rectLine.number, "rectification");
  if (rect[kIntrinsicCount] != 0.0) {
    throw vpHSlamException(vpHSlamException::invalidCalibration,
                           where + ": the fifth value of an explicit rectification must be 0");
  }
  double ofx = rect[0], ofy = rect[1], ocx = rect[2], ocy = rect[3];
  if (isRelative(ocx, ocy)) {
    relativeToPixels(outWidth, outHeight, ofx, ofy, ocx, ocy);
  }
  if (!(ofx > 0.0) || !(ofy > 0.0)) {
    throw vpHSlamException(vpHSlamException::invalidCalibration, where + ": rectified focal lengths must be positive");
  }
  vpCameraParameters K;
  try {
    K.initPersProjWithoutDistortion(ofx, ofy, ocx, ocy);
  } catch (const vpException &e) {
    // ViSP refuses a focal length that is positive but too small to invert (found by fuzz_camera_dso).
    throw vpHSlamException(vpHSlamException::invalidCalibration,
                           where + ": rectified intrinsics refused by ViSP (" + e.getStringMessage() + ")");
  }
  return K;
}

// Lines 3 (rectification target) and 4 (optional output size, default the input size) of a DSO camera.txt.
void applyDsoRectification(vpHSlamCamera &cam, const std::vector<hslam::TextLine> &lines, const std::string &path,
                           unsigned int width, unsigned int height)
{
  unsigned int outWidth = width, outHeight = height;
  if (lines.size() >= kDsoOutputSizeLine) {
    parseSizeLine(lines[kDsoOutputSizeLine - 1], path, "output image size", outWidth, outHeight);
  }

  const hslam::TextLine &rectLine = lines[kDsoRectificationLine - 1];
  const std::string where = fileLine(path, rectLine.number);
  const std::vector<std::string> tokens = hslam::splitWhitespace(rectLine.text);
  if (tokens.size() != 1) {
    const vpCameraParameters K = parseExplicitRectification(tokens, rectLine, path, outWidth, outHeight);
    applyRectification(cam, where, vpHSlamCamera::rectifyExplicit, outWidth, outHeight, K);
  } else if (tokens[0] == "crop") {
    applyRectification(cam, where, vpHSlamCamera::rectifyCrop, outWidth, outHeight);
  } else if (tokens[0] == "full") {
    applyRectification(cam, where, vpHSlamCamera::rectifyFull, outWidth, outHeight);
  } else if (tokens[0] == "none") {
    if (outWidth != width || outHeight != height) {
      // DSO: rectification "none" requires the output size to equal the input size.
      throw vpHSlamException(vpHSlamException::invalidCalibration,
                             fileLine(path, kDsoOutputSizeLine) + ": rectification 'none' needs the output size " +
                                 std::to_string(outWidth) + "x" + std::to_string(outHeight) +
                                 " to equal the input size " + std::to_string(width) + "x" + std::to_string(height));
    }
    applyRectification(cam, where, vpHSlamCamera::rectifyNone, outWidth, outHeight);
  } else {
    throw vpHSlamException(vpHSlamException::parseError,
                           where + ": rectification '" + tokens[0] + "' is not crop, full, none or 'fx fy cx cy 0'");
  }
}
} // namespace

vpHSlamCamera vpHSlamCamera::loadDso(const std::string &path)
{
  const std::vector<hslam::TextLine> lines = readDsoLines(path);

  // Line 1: model and parameters (fx fy cx cy, then the model's).
  const hslam::TextLine &modelLine = lines[kDsoModelLine - 1];
  const std::vector<std::string> tokens = hslam::splitWhitespace(modelLine.text);
  Model model = pinhole;
  std::vector<double> values;
  double unused = 0.0;
  if (hslam::tryParseDouble(tokens[0], unused)) {
    parseLegacyModelLine(tokens, modelLine, path, model, values);
  } else {
    parseKeywordModelLine(tokens, modelLine, path, model, values);
  }

  // Line 2: input size.
  if (lines.size() < kDsoInputSizeLine) {
    throw vpHSlamException(vpHSlamException::parseError,
                           fileLine(path, kDsoInputSizeLine) + ": missing input image size line 'width height'");
  }
  unsigned int width = 0, height = 0;
  parseSizeLine(lines[kDsoInputSizeLine - 1], path, "input image size", width, height);

  double fx = values[0], fy = values[1], cx = values[2], cy = values[3];
  if (isRelative(cx, cy)) {
    relativeToPixels(width, height, fx, fy, cx, cy);
  }
  const std::vector<double> distortion(values.begin() + kIntrinsicCount, values.end());
  vpHSlamCamera cam = makeCamera(fileLine(path, modelLine.number), model, width, height, fx, fy, cx, cy, distortion);

  if (lines.size() < kDsoRectificationLine) {
    setDefaultRectification(cam, path);
  } else {
    applyDsoRectification(cam, lines, path, width, height);
  }
  return cam;
}

vpHSlamCamera vpHSlamCamera::loadKittiCalib(const std::string &path, unsigned int width, unsigned int height,
                                            const std::string &projection)
{
  const std::vector<hslam::TextLine> lines = hslam::readTextLines(path);
  if (width == 0 || height == 0) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           path + ": KITTI calib.txt stores no image size; give width and height (got " +
                               std::to_string(width) + "x" + std::to_string(height) + ")");
  }
  const std::string key = projection + ":";
  for (const hslam::TextLine &line : lines) {
    const std::vector<std::string> tokens = hslam::splitWhitespace(line.text);
    if (tokens.empty() || tokens[0] != key) {
      continue;
    }
    hslam::expectTokenCount(tokens, 1 + kKittiProjectionCount, path, line.number, "'" + key + "' (3x4 matrix)");
    const std::vector<double> P = hslam::parseDoubles(tokens, 1, path, line.number, key);
    // Row-major 3x4: P = K [R | t] with K upper triangular and R = I for KITTI's rectified cameras.
    const double skew = P[1], p10 = P[4], p20 = P[8], p21 = P[9], p22 = P[10];
    if (std::fabs(skew) > kProjectionTolerance || std::fabs(p10) > kProjectionTolerance ||
        std::fabs(p20) > kProjectionTolerance || std::fabs(p21) > kProjectionTolerance ||
        std::fabs(p22 - 1.0) > kProjectionTolerance) {
      throw vpHSlamException(vpHSlamException::invalidCalibration,
                             fileLine(path, line.number) + ": '" + key +
                                 "' is not a rectified KITTI projection [fx 0 cx tx; 0 fy cy ty; 0 0 1 tz]");
    }
    vpHSlamCamera cam =
        makeCamera(fileLine(path, line.number), pinhole, width, height, P[0], P[5], P[2], P[6], std::vector<double>());
    setDefaultRectification(cam, path);
    return cam;
  }
  throw vpHSlamException(vpHSlamException::parseError, path + ": no '" + key + "' line");
}

vpHSlamCamera vpHSlamCamera::load(const std::string &path, unsigned int width, unsigned int height,
                                  const std::string &cameraName)
{
  hslam::requireFileExists(path, "calibration file");
  const std::size_t dot = path.find_last_of('.');
  const std::size_t slash = path.find_last_of('/');
  const std::string extension =
      (dot == std::string::npos || (slash != std::string::npos && dot < slash)) ? "" : hslam::toLower(path.substr(dot));
  if (extension == ".xml") {
    return loadViSPXml(path, cameraName, width, height);
  }
  if (extension == ".yaml" || extension == ".yml") {
    return loadEurocYaml(path);
  }
  // KITTI calib.txt is recognised by its projection line; every other text file is a DSO camera.txt.
  for (const hslam::TextLine &line : hslam::readTextLines(path)) {
    if (hslam::startsWith(hslam::trim(line.text), "P0:")) {
      return loadKittiCalib(path, width, height);
    }
  }
  return loadDso(path);
}
