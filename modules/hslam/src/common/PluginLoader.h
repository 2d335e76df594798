/*
 * H-SLAM for ViSP.
 */
//! \file PluginLoader.h  The module's plug-ins (modules/hslam/plugins/): shared objects loaded on first use.
#ifndef HSLAM_COMMON_PLUGIN_LOADER_H
#define HSLAM_COMMON_PLUGIN_LOADER_H

#include <visp3/core/vpConfig.h>

#include <string>

namespace hslam
{
/*!
  The entry point \e symbol of the plug-in \e file, loaded with dlopen() the first time it is asked for.

  Some of what the module can do needs third-party libraries that bring hundreds of shared libraries with them:
  OpenCV's video I/O (FFmpeg, GStreamer, GDAL, ...) and ViSP's detection module (which links ViSP's and OpenCV's
  image and video I/O). Linked into libvisp_hslam, they would be loaded by every program at start (about 0.5 s and
  tens of MB), while most runs never open a video nor look for a tag. They live in plug-ins instead, built and
  installed beside libvisp_hslam.

  Looked for at the path in the environment variable \e envVariable when it is set, otherwise beside libvisp_hslam,
  then on the loader's search path (LD_LIBRARY_PATH, ld.so.cache). A plug-in is loaded once and never unloaded
  (objects it made may outlive any caller). Thread-safe.

  \return the symbol; null, with \e error naming each place tried and why it failed, when the plug-in cannot be
  loaded (the same answer on later calls).
*/
VISP_EXPORT void *loadPluginSymbol(const char *file, const char *symbol, const char *envVariable, std::string &error);

//! loadPluginSymbol() of a function entry point, as the function pointer type \e Function.
template <typename Function>
Function loadPluginFunction(const char *file, const char *symbol, const char *envVariable, std::string &error)
{
  return reinterpret_cast<Function>(loadPluginSymbol(file, symbol, envVariable, error));
}
} // namespace hslam

#endif
