/*
 * H-SLAM for ViSP.
 */
#include "io/TumMonoSource.h"

#include "common/TextParsing.h"
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cctype>
#include <cstdint>

namespace hslam
{
using namespace io;

namespace
{
bool isDigits(const std::string &s)
{
  if (s.empty()) {
    return false;
  }
  for (unsigned char c : s) {
    if (!std::isdigit(c)) {
      return false;
    }
  }
  return true;
}
} // namespace

TumMonoSource::TumMonoSource(const std::string &path, const vpHSlamImageSource::Options &options)
    : IndexedImageSource(vpHSlamImageSource::formatTumMono, path)
{
  if (!pathIsDirectory(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "TUM monoVO folder '" + path + "' does not exist");
  }
  const std::string imageFolder = joinPath(path, "images");
  if (!pathIsDirectory(imageFolder)) {
    const std::string zip = joinPath(path, "images.zip");
    if (pathIsFile(zip)) {
      throw vpHSlamException(vpHSlamException::unsupported,
                             "'" + zip +
                                 "' cannot be read directly (no zip support in this build): unzip images.zip "
                                 "into images/ (cd '" +
                                 path + "' && mkdir images && unzip -q images.zip -d images)");
    }
    throw vpHSlamException(vpHSlamException::fileNotFound, "TUM monoVO folder '" + path + "' has no images/");
  }
  loadCamera(options, joinPath(path, "camera.txt"),
             [](const std::string &file) { return vpHSlamCamera::loadDso(file); });

  const std::string pcalib = joinPath(path, "pcalib.txt");
  const std::string vignette = joinPath(path, "vignette.png");
  if (pathIsFile(pcalib) || pathIsFile(vignette)) {
    m_photometric.load(pathIsFile(pcalib) ? pcalib : std::string(), pathIsFile(vignette) ? vignette : std::string(),
                       m_camera.getWidth(), m_camera.getHeight());
  }

  const std::vector<std::string> images = listImageFiles(imageFolder);
  const std::string timesFile = joinPath(path, "times.txt");
  const std::vector<TextLine> lines = readDataLines(timesFile, "TUM monoVO times list");
  if (lines.size() != images.size()) {
    throw vpHSlamException(vpHSlamException::invalidTimestamps,
                           "'" + timesFile + "' has " + std::to_string(lines.size()) + " lines but '" + imageFolder +
                               "' holds " + std::to_string(images.size()) + " images");
  }

  std::vector<IndexedFrame> frames(images.size());
  for (std::size_t i = 0; i < images.size(); ++i) {
    const TextLine &line = lines[i];
    const std::vector<std::string> fields = splitTokens(line.text, " \t");
    if (fields.size() < 2) {
      throw vpHSlamException(vpHSlamException::parseError, fileLine(timesFile, line.number) +
                                                               ": expected 'id time [exposure]', got '" + line.text +
                                                               "'");
    }
    const std::string stem = stemName(images[i]);
    // Pairing is by order; a numbered image whose number differs from the line's id means a list out of step.
    if (isDigits(fields[0]) && isDigits(stem) &&
        parseUInt64(fields[0], timesFile, line.number, "id") != parseUInt64(stem, images[i], 0, "image number")) {
      throw vpHSlamException(vpHSlamException::invalidTimestamps, fileLine(timesFile, line.number) + ": id " +
                                                                      fields[0] + " does not match image '" +
                                                                      images[i] + "' at the same position");
    }
    IndexedFrame &f = frames[i];
    f.path = joinPath(imageFolder, images[i]);
    f.timestamp = parseDouble(fields[1], timesFile, line.number, "time [s]");
    f.exposure = fields.size() >= 3 ? parseDouble(fields[2], timesFile, line.number, "exposure [ms]") : -1.;
    f.listFile = timesFile;
    f.line = line.number;
  }
  setFrames(std::move(frames), options);
}
} // namespace hslam
