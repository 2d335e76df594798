/*
 * H-SLAM for ViSP.
 */
#include "io/TumMonoSource.h"

#include "common/TextParsing.h"
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
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
  // images/ first: an unpacked folder is what the user last worked on when both exist.
  const std::string imageFolder = joinPath(path, "images");
  const std::string zipFile = joinPath(path, "images.zip");
  std::vector<std::string> images;
  std::string imageSource;
  if (pathIsDirectory(imageFolder)) {
    images = listImageFiles(imageFolder);
    imageSource = imageFolder;
  } else if (pathIsFile(zipFile)) {
    m_archive = std::make_unique<io::ZipArchive>(zipFile);
    for (const std::string &name : m_archive->fileNames()) {
      if (hasImageExtension(name) && baseName(name).front() != '.') {
        images.push_back(name);
      }
    }
    std::sort(images.begin(), images.end());
    imageSource = zipFile;
  } else {
    throw vpHSlamException(vpHSlamException::fileNotFound,
                           "TUM monoVO folder '" + path + "' has neither images/ nor images.zip");
  }
  loadCamera(options, joinPath(path, "camera.txt"),
             [](const std::string &file) { return vpHSlamCamera::loadDso(file); });
  loadFolderPhotometricCalibration(path);

  const std::string timesFile = joinPath(path, "times.txt");
  const std::vector<TextLine> lines = readListLines(timesFile, "TUM monoVO times list");
  // Pairs first, counts after: with numbered images, the first id out of step names the missing image.
  std::vector<IndexedFrame> frames(std::min(lines.size(), images.size()));
  std::size_t columns = 0;
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const TextLine &line = lines[i];
    const std::vector<std::string> fields = splitTokens(line.text, " \t");
    if (fields.size() < 2 || fields.size() > 3 || (columns != 0 && fields.size() != columns)) {
      throw vpHSlamException(vpHSlamException::parseError,
                             fileLine(timesFile, line.number) + ": expected 'id time [exposure]'" +
                                 (columns != 0 ? " with " + std::to_string(columns) + " columns like line " +
                                                     std::to_string(lines.front().number)
                                               : std::string()) +
                                 ", got '" + line.text + "'");
    }
    columns = fields.size();
    const std::string stem = stemName(images[i]);
    // Pairing is by order; a numbered image whose number differs from the line's id means a list out of step.
    if (isDigits(fields[0]) && isDigits(stem) &&
        parseUInt64(fields[0], timesFile, line.number, "id") != parseUInt64(stem, images[i], 0, "image number")) {
      throw vpHSlamException(vpHSlamException::invalidTimestamps,
                             fileLine(timesFile, line.number) + ": id " + fields[0] + " does not match image '" +
                                 images[i] + "' at the same position: image " + fields[0] + " missing from '" +
                                 imageSource + "', or a line too many");
    }
    IndexedFrame &f = frames[i];
    if (m_archive) {
      f.path = zipFile + ":" + images[i];
      f.entry = images[i];
    } else {
      f.path = joinPath(imageFolder, images[i]);
    }
    f.timestamp = parseDouble(fields[1], timesFile, line.number, "time [s]");
    f.exposure = fields.size() >= 3 ? parseDouble(fields[2], timesFile, line.number, "exposure [ms]") : -1.;
    f.listFile = timesFile;
    f.line = line.number;
  }
  if (lines.size() != images.size()) {
    throw vpHSlamException(vpHSlamException::invalidTimestamps,
                           "'" + timesFile + "' has " + std::to_string(lines.size()) + " lines but '" + imageSource +
                               "' holds " + std::to_string(images.size()) + " images");
  }
  setFrames(std::move(frames), options);
}

void TumMonoSource::readArchivedImage(const IndexedFrame &frame, vpImage<unsigned char> &I)
{
  m_archive->read(frame.entry, m_encoded);
  decodeGreyImage(m_encoded, frame.path, I);
}
} // namespace hslam
