/*
 * H-SLAM for ViSP.
 */
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>

#include "io/EurocSource.h"
#include "io/ImageSequenceSource.h"
#include "io/KittiSource.h"
#include "io/SourceFiles.h"
#include "io/TumMonoSource.h"
#include "io/TumRgbdSource.h"
#include "io/V4l2Source.h"
#include "io/VideoSource.h"

#include <utility>

namespace
{
using namespace hslam::io;

//! Names accepted on command lines, in Format order.
const std::pair<vpHSlamImageSource::Format, const char *> kFormatNames[] = {
    {vpHSlamImageSource::formatAuto, "auto"},        {vpHSlamImageSource::formatEuroc, "euroc"},
    {vpHSlamImageSource::formatTumMono, "tum-mono"}, {vpHSlamImageSource::formatTumRgbd, "tum-rgbd"},
    {vpHSlamImageSource::formatKitti, "kitti"},      {vpHSlamImageSource::formatImages, "images"},
    {vpHSlamImageSource::formatVideo, "video"},      {vpHSlamImageSource::formatV4l2, "v4l2"}};

bool isV4l2Device(const std::string &path)
{
  return path.rfind("/dev/video", 0) == 0;
}
} // namespace

vpHSlamImageSource::~vpHSlamImageSource() = default;

std::string vpHSlamImageSource::formatName(Format format)
{
  for (const auto &entry : kFormatNames) {
    if (entry.first == format) {
      return entry.second;
    }
  }
  return "unknown";
}

vpHSlamImageSource::Format vpHSlamImageSource::parseFormat(const std::string &name)
{
  std::string names;
  for (const auto &entry : kFormatNames) {
    if (name == entry.second) {
      return entry.first;
    }
    names += std::string(names.empty() ? "" : ", ") + entry.second;
  }
  throw vpHSlamException(vpHSlamException::invalidArgument,
                         "unknown input format '" + name + "' (expected one of " + names + ")");
}

vpHSlamImageSource::Format vpHSlamImageSource::detectFormat(const std::string &path)
{
  if (isV4l2Device(path)) {
    return formatV4l2;
  }
  if (path.find('%') != std::string::npos) {
    return hslam::isImagePattern(path) ? formatImages : formatAuto;
  }
  if (pathIsFile(path)) {
    return hasVideoExtension(path) ? formatVideo : formatAuto;
  }
  if (!pathIsDirectory(path)) {
    return formatAuto;
  }
  // Most specific layouts first: a KITTI or TUM folder may also hold loose images.
  if (!hslam::findEurocCameraFolder(path).empty()) {
    return formatEuroc;
  }
  const bool hasTimes = pathIsFile(joinPath(path, "times.txt"));
  if (hasTimes && pathIsDirectory(joinPath(path, "image_0"))) {
    return formatKitti;
  }
  if (hasTimes && (pathIsDirectory(joinPath(path, "images")) || pathIsFile(joinPath(path, "images.zip")))) {
    return formatTumMono;
  }
  if (pathIsFile(joinPath(path, "rgb.txt"))) {
    return formatTumRgbd;
  }
  try {
    if (!listImageFiles(path).empty()) {
      return formatImages;
    }
  } catch (const vpHSlamException &) {
    // An unlistable folder is simply not recognised.
  }
  return formatAuto;
}

std::unique_ptr<vpHSlamImageSource> vpHSlamImageSource::create(const std::string &path)
{
  return create(path, Options());
}

std::unique_ptr<vpHSlamImageSource> vpHSlamImageSource::create(const std::string &path, const Options &options)
{
  if (path.empty()) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "no input path given");
  }
  Format format = options.format;
  if (format == formatAuto) {
    format = detectFormat(path);
  }
  switch (format) {
  case formatEuroc:
    return std::make_unique<hslam::EurocSource>(path, options);
  case formatTumMono:
    return std::make_unique<hslam::TumMonoSource>(path, options);
  case formatTumRgbd:
    return std::make_unique<hslam::TumRgbdSource>(path, options);
  case formatKitti:
    return std::make_unique<hslam::KittiSource>(path, options);
  case formatImages:
    return std::make_unique<hslam::ImageSequenceSource>(path, options);
  case formatVideo:
    return std::make_unique<hslam::VideoSource>(path, options);
  case formatV4l2:
    return hslam::createV4l2Source(path, options);
  case formatAuto:
    break;
  }
  if (!pathIsFile(path) && !pathIsDirectory(path)) {
    throw vpHSlamException(vpHSlamException::fileNotFound, "input '" + path + "' does not exist");
  }
  throw vpHSlamException(
      vpHSlamException::unsupported,
      "cannot recognise the format of '" + path +
          "': expected an EuRoC/TUM-VI (mav0/cam0/data.csv), TUM monoVO (times.txt + images/ or images.zip), "
          "TUM RGB-D (rgb.txt), KITTI (times.txt + image_0/) or image folder, a printf pattern, "
          "a video file or /dev/videoN; or give the format explicitly (--format)");
}
