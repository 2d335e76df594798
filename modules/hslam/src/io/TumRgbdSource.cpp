/*
 * H-SLAM for ViSP.
 */
#include "io/TumRgbdSource.h"

#include "common/TextParsing.h"
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <sstream>

namespace hslam
{
using namespace io;

namespace
{
/*!
  Largest difference between a frame's time in rgb.txt and in times.txt, seconds: both lists are written with
  microseconds (TUM RGB-D's 6 decimals), so equal stamps differ by rounding only.
*/
constexpr double kTimeMatchTolerance = 1e-6;

bool isDigits(const std::string &s)
{
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

/*!
  H-SLAM extension of the layout: exposures from an optional times.txt ("id time[s] exposure[ms]"), one line per
  rgb.txt frame in the same order, as tutorial-hslam-synthetic writes it.
*/
void readExposures(const std::string &timesFile, const std::string &list, std::vector<IndexedFrame> &frames)
{
  const std::vector<TextLine> lines = readListLines(timesFile, "exposure list");
  if (lines.size() != frames.size()) {
    throw vpHSlamException(vpHSlamException::invalidTimestamps,
                           "'" + timesFile + "' has " + std::to_string(lines.size()) + " lines but '" + list +
                               "' lists " + std::to_string(frames.size()) + " images: one exposure per frame");
  }
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const TextLine &line = lines[i];
    IndexedFrame &f = frames[i];
    const std::vector<std::string> fields = splitTokens(line.text, " \t");
    if (fields.size() != 3) {
      throw vpHSlamException(vpHSlamException::parseError, fileLine(timesFile, line.number) +
                                                               ": expected 'id time[s] exposure[ms]', got '" +
                                                               line.text + "'");
    }
    const double time = parseDouble(fields[1], timesFile, line.number, "time [s]");
    const std::string stem = stemName(f.path);
    const bool idMismatch =
        isDigits(fields[0]) && isDigits(stem) &&
        parseUInt64(fields[0], timesFile, line.number, "id") != parseUInt64(stem, f.path, 0, "image number");
    if (idMismatch || !(std::abs(time - f.timestamp) <= kTimeMatchTolerance)) {
      std::ostringstream msg;
      msg.precision(17);
      msg << fileLine(timesFile, line.number) << ": '" << line.text << "' does not match frame " << i << " of "
          << fileLine(list, f.line) << " (time " << f.timestamp << " s, image '" << baseName(f.path)
          << "'): times.txt must list the frames of rgb.txt, in the same order";
      throw vpHSlamException(vpHSlamException::invalidTimestamps, msg.str());
    }
    f.exposure = parseDouble(fields[2], timesFile, line.number, "exposure [ms]");
  }
}
} // namespace

std::string findFolderCameraFile(const std::string &folder, const vpHSlamImageSource::Options &options)
{
  if (!options.cameraFile.empty()) {
    return options.cameraFile;
  }
  for (const char *name : {"camera.txt", "camera.xml", "camera.yaml"}) {
    const std::string file = joinPath(folder, name);
    if (pathIsFile(file)) {
      return file;
    }
  }
  return std::string();
}

TumRgbdSource::TumRgbdSource(const std::string &path, const vpHSlamImageSource::Options &options)
    : IndexedImageSource(vpHSlamImageSource::formatTumRgbd, path)
{
  if (!pathIsDirectory(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "TUM RGB-D folder '" + path + "' does not exist");
  }
  const std::string cameraFile = findFolderCameraFile(path, options);
  if (cameraFile.empty()) {
    throw vpHSlamException(vpHSlamException::fileNotFound,
                           "no camera file for '" + path +
                               "': give one (Options::cameraFile, --camera) or put camera.txt or camera.xml there");
  }
  const std::string list = joinPath(path, "rgb.txt");
  std::vector<IndexedFrame> frames;
  for (const TextLine &line : readListLines(list, "TUM RGB-D image list")) {
    const std::vector<std::string> fields = splitTokens(line.text, " \t");
    if (fields.size() < 2) {
      throw vpHSlamException(vpHSlamException::parseError,
                             fileLine(list, line.number) + ": expected 'timestamp filename', got '" + line.text + "'");
    }
    IndexedFrame f;
    f.timestamp = parseDouble(fields[0], list, line.number, "timestamp [s]");
    f.path = joinPath(path, fields[1]);
    f.listFile = list;
    f.line = line.number;
    frames.push_back(f);
  }
  if (frames.empty()) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "'" + list + "' lists no image");
  }
  // The first image gives the size to calibration formats that do not store it (KITTI calib.txt).
  vpImage<unsigned char> first;
  readGreyImage(frames.front().path, first);
  vpHSlamImageSource::Options withCamera = options;
  withCamera.cameraFile = cameraFile;
  loadCamera(
      withCamera, cameraFile, [](const std::string &file) { return vpHSlamCamera::load(file); }, first.getWidth(),
      first.getHeight());
  loadFolderPhotometricCalibration(path);
  const std::string timesFile = joinPath(path, "times.txt");
  if (pathIsFile(timesFile)) {
    readExposures(timesFile, list, frames);
  }
  setFrames(std::move(frames), options);
}
} // namespace hslam
