/*
 * H-SLAM for ViSP.
 */
#include "io/VideoDecoder.h"

#include "common/PluginLoader.h"

#include <visp3/hslam/vpHSlamException.h>

#include <string>

namespace hslam
{
namespace io
{
namespace
{
using Factory = VideoDecoder *(*)(const char *, std::string *);
} // namespace

std::unique_ptr<VideoDecoder> openVideoDecoder(const std::string &path)
{
  std::string error;
  const auto factory = loadPluginFunction<Factory>(kVideoPluginFile, kVideoPluginFactory, "HSLAM_VIDEO_PLUGIN", error);
  if (factory == nullptr) {
    throw vpHSlamException(vpHSlamException::unsupported,
                           "cannot open video '" + path + "': video files are decoded by a plug-in: " + error);
  }
  VideoDecoder *decoder = factory(path.c_str(), &error);
  if (decoder == nullptr) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot open video '" + path + "': " + error);
  }
  return std::unique_ptr<VideoDecoder>(decoder);
}
} // namespace io
} // namespace hslam
