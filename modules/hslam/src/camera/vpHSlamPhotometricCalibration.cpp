/*
 * H-SLAM for ViSP.
 */
// Photometric calibration (TUM monoVO model, Engel et al. 2016): B(x) = G(I(x)) / (t V(x)).
//
// Conventions follow DSO's PhotometricUndistorter (src/util/Undistort.cpp): G is rescaled affinely to [0, 255],
// the vignette is divided by its maximum and inverted once at load time, and the per-frame work is a table lookup
// and one multiplication per pixel.

#include "io/ImageCodec.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamPhotometricCalibration.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

namespace hslam
{
namespace
{
//! Number of entries of the inverse response: one per 8-bit intensity.
constexpr std::size_t kResponseSize = 256;
//! DSO convention: G is rescaled so that G(0) = 0 and G(255) = kResponseMax (irradiance in intensity units).
constexpr double kResponseMax = 255.0;

std::string quoted(const std::string &text)
{
  return "'" + text + "'";
}

/*!
  Check an inverse response and rescale it to [0, kResponseMax].
  \param values : raw values, in file order.
  \param source : what to name in error messages (a file path, or the API call).
*/
std::vector<float> validateAndRescaleResponse(const std::vector<double> &values, const std::string &source)
{
  if (values.size() != kResponseSize) {
    std::ostringstream msg;
    msg << source << ": inverse response needs exactly " << kResponseSize << " values, found " << values.size();
    throw vpHSlamException(vpHSlamException::invalidCalibration, msg.str());
  }
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) {
      std::ostringstream msg;
      msg << source << ": inverse response value G(" << i << ") = " << values[i] << " is not a finite number";
      throw vpHSlamException(vpHSlamException::invalidCalibration, msg.str());
    }
    if (i > 0 && values[i] < values[i - 1]) {
      std::ostringstream msg;
      msg << source << ": inverse response must be non-decreasing, but G(" << i << ") = " << values[i] << " < G("
          << (i - 1) << ") = " << values[i - 1];
      throw vpHSlamException(vpHSlamException::invalidCalibration, msg.str());
    }
  }
  const double gMin = values.front();
  const double gMax = values.back();
  if (!(gMax > gMin)) {
    std::ostringstream msg;
    msg << source << ": inverse response is constant (G(0) = G(255) = " << gMin << "), it cannot be rescaled";
    throw vpHSlamException(vpHSlamException::invalidCalibration, msg.str());
  }
  // DSO: G <- 255 (G - G(0)) / (G(255) - G(0)). Computed in double, stored in float (the lookup table type).
  const double scale = kResponseMax / (gMax - gMin);
  std::vector<float> rescaled(kResponseSize);
  for (std::size_t i = 0; i < kResponseSize; ++i) {
    rescaled[i] = static_cast<float>((values[i] - gMin) * scale);
  }
  return rescaled;
}

void requireExisting(const std::string &path, const char *what)
{
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, quoted(path) + ": " + what + " file not found");
  }
  if (std::filesystem::is_directory(path, ec)) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           quoted(path) + ": " + what + " path is a folder, not a file");
  }
}

//! Read every whitespace-separated number of pcalib.txt (one or several lines), with line numbers for errors.
std::vector<double> readResponseFile(const std::string &path)
{
  requireExisting(path, "inverse response");
  std::ifstream file(path);
  if (!file.is_open()) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, quoted(path) + ": cannot open the inverse response file");
  }
  std::vector<double> values;
  values.reserve(kResponseSize);
  std::string line;
  unsigned int lineNumber = 0;
  while (std::getline(file, line)) {
    ++lineNumber;
    std::istringstream tokens(line);
    std::string token;
    while (tokens >> token) {
      // strtod accepts "nan" and "inf": they parse here and are rejected as invalid values with their index.
      char *end = nullptr;
      const double value = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') {
        std::ostringstream msg;
        msg << path << ":" << lineNumber << ": value " << (values.size() + 1) << " '" << token << "' is not a number";
        throw vpHSlamException(vpHSlamException::parseError, msg.str());
      }
      values.push_back(value);
    }
  }
  if (file.bad()) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, quoted(path) + ": read error");
  }
  return values;
}

//! Turn raw vignette samples (any positive scale) into 1/V with V normalised to a maximum of 1.
template <typename T>
void buildInverseVignette(const T *samples, unsigned int width, unsigned int height, const std::string &source,
                          vpImage<float> &invV)
{
  const std::size_t count = static_cast<std::size_t>(width) * height;
  double vMax = 0.0;
  for (std::size_t k = 0; k < count; ++k) {
    const double v = static_cast<double>(samples[k]);
    if (!(v > 0.0) || !std::isfinite(v)) {
      std::ostringstream msg;
      msg << source << ": vignette value " << v << " at pixel (x=" << (k % width) << ", y=" << (k / width)
          << ") must be finite and > 0";
      throw vpHSlamException(vpHSlamException::invalidCalibration, msg.str());
    }
    vMax = std::max(vMax, v);
  }
  // DSO: V <- V / max(V), then 1/V precomputed so the per-frame pass multiplies only.
  invV.resize(height, width);
  float *dst = invV.bitmap;
  for (std::size_t k = 0; k < count; ++k) {
    dst[k] = static_cast<float>(vMax / static_cast<double>(samples[k]));
  }
}

//! Read a vignette image at its own bit depth (8 or 16 bits; ViSP 3.5's vpImageIo would reduce 16-bit PNGs to 8).
void readVignetteFile(const std::string &path, unsigned int width, unsigned int height, vpImage<float> &invV)
{
  requireExisting(path, "vignette");
  if (width == 0 || height == 0) {
    std::ostringstream msg;
    msg << quoted(path) << ": expected vignette size " << width << "x" << height << " is empty";
    throw vpHSlamException(vpHSlamException::invalidArgument, msg.str());
  }
  std::vector<std::uint16_t> samples;
  unsigned int w = 0, h = 0;
  int depth = 8; // not needed: the vignette is normalised to its maximum
  try {
    // 16-bit files keep their 16 bits; colour files are converted to grey.
    const std::vector<unsigned char> bytes = io::readFileBytes(path);
    io::decodeGreyAnyDepth(bytes.data(), bytes.size(), path, samples, w, h, depth);
  } catch (const vpHSlamException &e) {
    throw vpHSlamException(vpHSlamException::fileUnreadable,
                           quoted(path) + ": cannot decode the vignette image (" + e.getStringMessage() + ")");
  }
  if (w != width || h != height) {
    std::ostringstream msg;
    msg << quoted(path) << ": vignette is " << w << "x" << h << " pixels, expected " << width << "x" << height
        << " (the input image size)";
    throw vpHSlamException(vpHSlamException::invalidCalibration, msg.str());
  }
  buildInverseVignette(samples.data(), width, height, quoted(path), invV); // scale-free: 8 or 16 bits alike
}
} // namespace
} // namespace hslam

vpHSlamPhotometricCalibration::vpHSlamPhotometricCalibration() = default;

void vpHSlamPhotometricCalibration::load(const std::string &responseFile, const std::string &vignetteFile,
                                         unsigned int width, unsigned int height)
{
  // All-or-nothing: build the new state aside, commit only when every file is valid.
  std::vector<float> G;
  if (!responseFile.empty()) {
    G = hslam::validateAndRescaleResponse(hslam::readResponseFile(responseFile), hslam::quoted(responseFile));
  }
  vpImage<float> invV;
  if (!vignetteFile.empty()) {
    hslam::readVignetteFile(vignetteFile, width, height, invV);
  }
  m_G = std::move(G);
  m_invV = invV;
  m_responseFile = responseFile;
  m_vignetteFile = vignetteFile;
}

void vpHSlamPhotometricCalibration::setInverseResponse(const std::vector<double> &G)
{
  m_G = hslam::validateAndRescaleResponse(G, "vpHSlamPhotometricCalibration::setInverseResponse()");
  m_responseFile.clear();
}

void vpHSlamPhotometricCalibration::setVignette(const vpImage<float> &V)
{
  const char *source = "vpHSlamPhotometricCalibration::setVignette()";
  if (V.getSize() == 0) {
    throw vpHSlamException(vpHSlamException::invalidCalibration, std::string(source) + ": empty vignette image");
  }
  vpImage<float> invV;
  hslam::buildInverseVignette(V.bitmap, V.getWidth(), V.getHeight(), source, invV);
  m_invV = invV;
  m_vignetteFile.clear();
}

void vpHSlamPhotometricCalibration::toIrradiance(const vpImage<unsigned char> &I, double exposure,
                                                 vpImage<float> &B) const
{
  const bool withVignette = hasVignette();
  if (withVignette && (I.getWidth() != m_invV.getWidth() || I.getHeight() != m_invV.getHeight())) {
    std::ostringstream msg;
    msg << "vpHSlamPhotometricCalibration::toIrradiance(): image is " << I.getWidth() << "x" << I.getHeight()
        << " pixels, the vignette " << m_invV.getWidth() << "x" << m_invV.getHeight();
    throw vpHSlamException(vpHSlamException::invalidImage, msg.str());
  }

  // 1/t is folded into the 256-entry table (on the stack): the pixel loop is one lookup and at most one multiply.
  const float invExposure = (exposure > 0.0 && std::isfinite(exposure)) ? static_cast<float>(1.0 / exposure) : 1.0f;
  std::array<float, hslam::kResponseSize> lut;
  const bool withResponse = hasResponse();
  for (std::size_t i = 0; i < lut.size(); ++i) {
    lut[i] = (withResponse ? m_G[i] : static_cast<float>(i)) * invExposure;
  }

  if (B.getWidth() != I.getWidth() || B.getHeight() != I.getHeight()) {
    B.resize(I.getHeight(), I.getWidth());
  }
  const std::size_t count = I.getSize();
  const unsigned char *src = I.bitmap;
  float *dst = B.bitmap;
  if (withVignette) {
    const float *invV = m_invV.bitmap;
    for (std::size_t k = 0; k < count; ++k) {
      dst[k] = lut[src[k]] * invV[k];
    }
  } else {
    for (std::size_t k = 0; k < count; ++k) {
      dst[k] = lut[src[k]];
    }
  }
}

std::string vpHSlamPhotometricCalibration::getStatus() const
{
  if (isEmpty()) {
    return "photometric calibration: none (affine brightness estimated)";
  }
  std::ostringstream status;
  status << "photometric calibration: inverse response ";
  if (!hasResponse()) {
    status << "none (linear)";
  } else if (m_responseFile.empty()) {
    status << "set directly";
  } else {
    status << "from " << hslam::quoted(m_responseFile);
  }
  status << ", vignette ";
  if (!hasVignette()) {
    status << "none";
  } else {
    status << (m_vignetteFile.empty() ? std::string("set directly") : "from " + hslam::quoted(m_vignetteFile)) << " ("
           << m_invV.getWidth() << "x" << m_invV.getHeight() << ")";
  }
  return status.str();
}
