/*
 * H-SLAM for ViSP.
 */
#include "io/ImageSequenceSource.h"

#include "io/SourceFiles.h"
#include "io/TumRgbdSource.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

namespace hslam
{
using namespace io;

namespace
{
//! Longest file name a pattern may produce.
constexpr std::size_t kMaxPathLength = 4096;
//! Longest digit run taken for a frame number (fits unsigned int).
constexpr std::size_t kMaxIndexDigits = 9;

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

/*!
  Smallest-numbered file of \e pattern's folder that the pattern produces for a number above \e gap, empty when
  none. Only a conversion in the file name is searched (not in a folder component).
*/
std::string firstFileAfter(const std::string &pattern, unsigned int gap)
{
  const std::string folder = parentPath(pattern);
  const std::string namePattern = baseName(pattern);
  const std::size_t percent = namePattern.find('%');
  if (percent == std::string::npos || !pathIsDirectory(folder)) {
    return std::string();
  }
  const std::size_t conversionEnd = namePattern.find_first_of("du", percent);
  const std::string prefix = namePattern.substr(0, percent), suffix = namePattern.substr(conversionEnd + 1);
  std::string best;
  unsigned long bestIndex = 0;
  std::error_code ec;
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() + suffix.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - suffix.size(), suffix.size(), suffix) != 0) {
      continue;
    }
    const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
    if (digits.size() > kMaxIndexDigits ||
        !std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c) != 0; })) {
      continue;
    }
    const unsigned long index = std::stoul(digits);
    // The pattern must give back this very name (same zero padding), else it is another sequence.
    if (index > gap && (best.empty() || index < bestIndex) &&
        formatPattern(pattern, static_cast<unsigned int>(index)) == joinPath(folder, name)) {
      best = joinPath(folder, name);
      bestIndex = index;
    }
  }
  return best;
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
  if (!files.empty()) {
    const std::string after = firstFileAfter(pattern, index);
    if (!after.empty()) {
      throw vpHSlamException(vpHSlamException::fileNotFound,
                             "image pattern '" + pattern + "': '" + formatPattern(pattern, index) +
                                 "' does not exist but '" + after +
                                 "' does: a frame is missing from the numbered sequence (frames after it would be "
                                 "dropped); restore it, or renumber the files");
    }
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
