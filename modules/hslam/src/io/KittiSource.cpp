/*
 * H-SLAM for ViSP.
 */
#include "io/KittiSource.h"

#include "common/TextParsing.h"
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cstdio>

namespace hslam
{
using namespace io;

namespace
{
//! KITTI odometry names frame i "%06d.png".
std::string kittiImageName(std::size_t index)
{
  char name[32];
  std::snprintf(name, sizeof(name), "%06zu.png", index);
  return name;
}
} // namespace

KittiSource::KittiSource(const std::string &path, const vpHSlamImageSource::Options &options)
    : IndexedImageSource(vpHSlamImageSource::formatKitti, path)
{
  if (!pathIsDirectory(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "KITTI folder '" + path + "' does not exist");
  }
  const std::string imageFolder = joinPath(path, "image_0");
  const std::string timesFile = joinPath(path, "times.txt");
  const std::vector<TextLine> lines = readListLines(timesFile, "KITTI times list");
  const std::vector<std::string> images = listImageFiles(imageFolder);

  std::vector<IndexedFrame> frames(lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const TextLine &line = lines[i];
    const std::vector<std::string> fields = splitTokens(line.text, " \t");
    if (fields.size() != 1) {
      throw vpHSlamException(vpHSlamException::parseError, fileLine(timesFile, line.number) +
                                                               ": expected one time in seconds, got '" + line.text +
                                                               "'");
    }
    IndexedFrame &f = frames[i];
    f.timestamp = parseDouble(fields[0], timesFile, line.number, "time [s]");
    f.path = joinPath(imageFolder, kittiImageName(i));
    f.listFile = timesFile;
    f.line = line.number;
    if (!pathIsFile(f.path)) {
      throw vpHSlamException(vpHSlamException::fileNotFound, "image '" + f.path + "' (frame " + std::to_string(i) +
                                                                 " of " + fileLine(timesFile, line.number) +
                                                                 ") does not exist");
    }
  }
  if (images.size() != lines.size()) {
    throw vpHSlamException(vpHSlamException::invalidTimestamps,
                           "'" + timesFile + "' has " + std::to_string(lines.size()) + " lines but '" + imageFolder +
                               "' holds " + std::to_string(images.size()) + " images");
  }
  if (frames.empty()) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "'" + timesFile + "' lists no frame");
  }

  vpImage<unsigned char> first;
  readGreyImage(frames.front().path, first);
  loadCamera(
      options, joinPath(path, "calib.txt"),
      [&first](const std::string &file) {
        return vpHSlamCamera::loadKittiCalib(file, first.getWidth(), first.getHeight());
      },
      first.getWidth(), first.getHeight());
  setFrames(std::move(frames), options);
}
} // namespace hslam
