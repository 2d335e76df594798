/*
 * H-SLAM for ViSP.
 */
#include "io/VideoDecoder.h"

#include <visp3/hslam/vpHSlamException.h>

#include <dlfcn.h>

#include <cstdlib>
#include <mutex>
#include <string>
#include <vector>

namespace hslam
{
namespace io
{
namespace
{
using Factory = VideoDecoder *(*)(const char *, std::string *);

//! The directory of the shared library this function is in (libvisp_hslam), empty when unknown.
std::string moduleDirectory()
{
  Dl_info info{};
  if (dladdr(reinterpret_cast<void *>(&moduleDirectory), &info) == 0 || info.dli_fname == nullptr) {
    return std::string();
  }
  const std::string file = info.dli_fname;
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? std::string() : file.substr(0, slash);
}

//! The plug-in's factory, loaded once (never unloaded: decoders it made may outlive any caller); null with
//! \e error set when it cannot be loaded.
Factory loadFactory(std::string &error)
{
  static std::mutex mutex;
  static Factory factory = nullptr;
  static std::string loadError;
  std::lock_guard<std::mutex> lock(mutex);
  if (factory == nullptr && loadError.empty()) {
    std::vector<std::string> candidates;
    if (const char *explicitPath = std::getenv("HSLAM_VIDEO_PLUGIN")) {
      candidates.emplace_back(explicitPath);
    } else {
      const std::string dir = moduleDirectory();
      if (!dir.empty()) {
        candidates.push_back(dir + "/" + kVideoPluginFile);
      }
      candidates.emplace_back(kVideoPluginFile); // the loader's search path (LD_LIBRARY_PATH, ld.so.cache)
    }
    std::string tried;
    for (const std::string &candidate : candidates) {
      void *handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        const char *why = dlerror();
        tried += "\n  " + candidate + ": " + (why != nullptr ? why : "not loadable");
        continue;
      }
      factory = reinterpret_cast<Factory>(dlsym(handle, kVideoPluginFactory));
      if (factory == nullptr) {
        tried += "\n  " + candidate + ": no " + kVideoPluginFactory + " in it";
        continue;
      }
      break;
    }
    if (factory == nullptr) {
      loadError = "video files are decoded by the plug-in " + std::string(kVideoPluginFile) +
                  " (built with the module, installed beside libvisp_hslam; HSLAM_VIDEO_PLUGIN may name it), which "
                  "could not be loaded:" +
                  tried;
    }
  }
  error = loadError;
  return factory;
}
} // namespace

std::unique_ptr<VideoDecoder> openVideoDecoder(const std::string &path)
{
  std::string error;
  const Factory factory = loadFactory(error);
  if (factory == nullptr) {
    throw vpHSlamException(vpHSlamException::unsupported, "cannot open video '" + path + "': " + error);
  }
  VideoDecoder *decoder = factory(path.c_str(), &error);
  if (decoder == nullptr) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot open video '" + path + "': " + error);
  }
  return std::unique_ptr<VideoDecoder>(decoder);
}
} // namespace io
} // namespace hslam
