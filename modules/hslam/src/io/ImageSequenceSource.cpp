/*
 * H-SLAM for ViSP.
 */
#include "io/ImageSequenceSource.h"

#include "io/SourceFiles.h"
#include "io/TumRgbdSource.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cctype>
#include <cstdio>

namespace hslam
{
using namespace io;

namespace
{
//! Longest file name a pattern may produce.
constexpr std::size_t kMaxPathLength = 4096;

std::string formatPattern(const std::string &pattern, unsigned int index)
{
  std::vector<char> buffer(kMaxPathLength);
  // The pattern was validated by isImagePattern(): one integer conversion, nothing else.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
  const int n = std::snprintf(buffer.data(), buffer.size(), pattern.c_str(), index);
#pragma GCC diagnostic pop
  if (n < 0 || static_cast<std::size_t>(n) >= buffer.size()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "image pattern '" + pattern + "' gives a too long name");
  }
  return std::string(buffer.data(), static_cast<std::size_t>(n));
}
} // namespace

bool isImagePattern(const std::string &pattern)
{
  int conversions = 0;
  for (std::size_t i = 0; i < pattern.size(); ++i) {
    if (pattern[i] != '%') {
      continue;
    }
    std::size_t j = i + 1;
    while (j < pattern.size() && std::isdigit(static_cast<unsigned char>(pattern[j]))) {
      ++j;
    }
    if (j >= pattern.size() || (pattern[j] != 'd' && pattern[j] != 'u')) {
      return false;
    }
    ++conversions;
    i = j;
  }
  return conversions == 1;
}

std::vector<std::string> expandImagePattern(const std::string &pattern, unsigned int maxFirstIndex)
{
  if (!isImagePattern(pattern)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "image pattern '" + pattern + "' must hold exactly one integer conversion such as %06d");
  }
  std::vector<std::string> files;
  unsigned int index = 0;
  while (index < maxFirstIndex && !pathIsFile(formatPattern(pattern, index))) {
    ++index;
  }
  for (; pathIsFile(formatPattern(pattern, index)); ++index) {
    files.push_back(formatPattern(pattern, index));
  }
  return files;
}

ImageSequenceSource::ImageSequenceSource(const std::string &path, const vpHSlamImageSource::Options &options)
    : IndexedImageSource(vpHSlamImageSource::formatImages, path)
{
  if (!(options.frameRate > 0.)) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "image sequence '" + path + "' needs a positive frame rate (Options::frameRate, --fps)");
  }
  std::vector<std::string> files;
  std::string folder;
  if (path.find('%') != std::string::npos) {
    files = expandImagePattern(path);
    folder = parentPath(path);
    if (files.empty()) {
      throw vpHSlamException(vpHSlamException::fileNotFound, "no file matches the image pattern '" + path + "'");
    }
  } else {
    folder = path;
    for (const std::string &name : listImageFiles(path)) {
      files.push_back(joinPath(path, name));
    }
    if (files.empty()) {
      throw vpHSlamException(vpHSlamException::fileNotFound, "image folder '" + path + "' holds no image");
    }
  }

  const std::string cameraFile = findFolderCameraFile(folder, options);
  if (cameraFile.empty()) {
    throw vpHSlamException(vpHSlamException::fileNotFound,
                           "no camera file for '" + path +
                               "': give one (Options::cameraFile, --camera) or put camera.txt or camera.xml in '" +
                               folder + "'");
  }
  // The first image gives the size to calibration formats that do not store it (KITTI calib.txt).
  vpImage<unsigned char> first;
  readGreyImage(files.front(), first);
  vpHSlamImageSource::Options withCamera = options;
  withCamera.cameraFile = cameraFile;
  loadCamera(
      withCamera, cameraFile, [](const std::string &file) { return vpHSlamCamera::load(file); }, first.getWidth(),
      first.getHeight());

  std::vector<IndexedFrame> frames(files.size());
  for (std::size_t i = 0; i < files.size(); ++i) {
    frames[i].path = files[i];
    frames[i].timestamp = static_cast<double>(i) / options.frameRate;
  }
  setFrames(std::move(frames), options, options.frameRate);
}
} // namespace hslam
