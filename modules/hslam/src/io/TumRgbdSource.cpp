/*
 * H-SLAM for ViSP.
 */
#include "io/TumRgbdSource.h"

#include "common/TextParsing.h"
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

namespace hslam
{
using namespace io;

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
  for (const TextLine &line : readDataLines(list, "TUM RGB-D image list")) {
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
  setFrames(std::move(frames), options);
}
} // namespace hslam
