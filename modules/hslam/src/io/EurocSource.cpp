/*
 * H-SLAM for ViSP.
 */
#include "io/EurocSource.h"

#include "common/TextParsing.h"
#include "io/SourceFiles.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cstdint>
#include <map>

namespace hslam
{
using namespace io;

namespace
{
//! ASL timestamps are integer nanoseconds.
constexpr std::uint64_t kNanosecondsPerSecond = 1000000000ULL;

//! Seconds and nanoseconds converted apart, so the only rounding is the final addition's.
double nanosecondsToSeconds(std::uint64_t ns)
{
  return static_cast<double>(ns / kNanosecondsPerSecond) +
         static_cast<double>(ns % kNanosecondsPerSecond) / static_cast<double>(kNanosecondsPerSecond);
}

bool isCameraFolder(const std::string &folder)
{
  return pathIsFile(joinPath(folder, "data.csv")) && pathIsDirectory(joinPath(folder, "data"));
}

//! TUM-VI's DSO export: nanosecond stamp -> exposure in milliseconds.
std::map<std::uint64_t, double> readTumViExposures(const std::string &timesFile)
{
  std::map<std::uint64_t, double> exposures;
  for (const TextLine &line : readListLines(timesFile, "TUM-VI exposure list")) {
    const std::vector<std::string> fields = splitTokens(line.text, " \t,");
    if (fields.size() < 3) {
      throw vpHSlamException(vpHSlamException::parseError,
                             fileLine(timesFile, line.number) +
                                 ": expected 'timestamp[ns] timestamp[s] exposure[ms]', got '" + line.text + "'");
    }
    const std::uint64_t ns = parseUInt64(fields[0], timesFile, line.number, "timestamp [ns]");
    exposures[ns] = parseDouble(fields[2], timesFile, line.number, "exposure [ms]");
  }
  return exposures;
}
} // namespace

std::string findEurocCameraFolder(const std::string &path)
{
  for (const char *sub : {"mav0/cam0", "cam0", ""}) {
    const std::string folder = *sub ? joinPath(path, sub) : path;
    if (isCameraFolder(folder)) {
      return folder;
    }
  }
  return std::string();
}

EurocSource::EurocSource(const std::string &path, const vpHSlamImageSource::Options &options)
    : IndexedImageSource(vpHSlamImageSource::formatEuroc, path)
{
  if (!pathIsDirectory(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "EuRoC folder '" + path + "' does not exist");
  }
  std::string camFolder = findEurocCameraFolder(path);
  if (camFolder.empty()) {
    const std::string expected = joinPath(path, "mav0/cam0/data.csv");
    throw vpHSlamException(vpHSlamException::fileNotFound,
                           "'" + path + "' is not an EuRoC/ASL folder: '" + expected + "' (and data/) not found");
  }
  loadCamera(options, joinPath(camFolder, "sensor.yaml"),
             [](const std::string &file) { return vpHSlamCamera::loadEurocYaml(file); });

  // TUM-VI: the sequence folder is the parent of mav0.
  const std::string seqFolder = parentPath(parentPath(camFolder));
  const std::string dsoFolder = joinPath(seqFolder, "dso/" + baseName(camFolder));
  std::map<std::uint64_t, double> exposures;
  if (pathIsFile(joinPath(dsoFolder, "times.txt"))) {
    exposures = readTumViExposures(joinPath(dsoFolder, "times.txt"));
  }
  loadFolderPhotometricCalibration(dsoFolder);

  const std::string csv = joinPath(camFolder, "data.csv");
  const std::string dataFolder = joinPath(camFolder, "data");
  std::vector<IndexedFrame> frames;
  for (const TextLine &line : readListLines(csv, "EuRoC image list")) {
    const std::vector<std::string> fields = splitTokens(line.text, ",");
    if (fields.size() < 2) {
      throw vpHSlamException(vpHSlamException::parseError, fileLine(csv, line.number) +
                                                               ": expected 'timestamp [ns],filename', got '" +
                                                               line.text + "'");
    }
    const std::uint64_t ns = parseUInt64(fields[0], csv, line.number, "timestamp [ns]");
    IndexedFrame f;
    f.path = joinPath(dataFolder, fields[1]);
    f.timestamp = nanosecondsToSeconds(ns);
    const auto exposure = exposures.find(ns);
    f.exposure = exposure != exposures.end() ? exposure->second : -1.;
    f.listFile = csv;
    f.line = line.number;
    frames.push_back(f);
  }
  setFrames(std::move(frames), options);
}
} // namespace hslam
