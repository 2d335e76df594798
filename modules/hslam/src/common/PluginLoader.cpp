/*
 * H-SLAM for ViSP.
 */
#include "common/PluginLoader.h"

#include <dlfcn.h>

#include <cstdlib>
#include <map>
#include <mutex>
#include <vector>

namespace hslam
{
namespace
{
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

//! One symbol's outcome: the symbol, or why it could not be had.
struct Loaded {
  void *symbol = nullptr;
  std::string error;
};

Loaded load(const char *file, const char *symbol, const char *envVariable)
{
  std::vector<std::string> candidates;
  if (const char *explicitPath = std::getenv(envVariable)) {
    candidates.emplace_back(explicitPath);
  } else {
    const std::string dir = moduleDirectory();
    if (!dir.empty()) {
      candidates.push_back(dir + "/" + file);
    }
    candidates.emplace_back(file);
  }
  Loaded out;
  std::string tried;
  for (const std::string &candidate : candidates) {
    void *handle = dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char *why = dlerror();
      tried += "\n  " + candidate + ": " + (why != nullptr ? why : "not loadable");
      continue;
    }
    out.symbol = dlsym(handle, symbol);
    if (out.symbol != nullptr) {
      return out;
    }
    tried += "\n  " + candidate + ": no " + symbol + " in it";
  }
  out.error = "the plug-in " + std::string(file) + " (built with the module, installed beside libvisp_hslam; " +
              envVariable + " may name it) could not be loaded:" + tried;
  return out;
}
} // namespace

void *loadPluginSymbol(const char *file, const char *symbol, const char *envVariable, std::string &error)
{
  static std::mutex mutex;
  static std::map<std::string, Loaded> loaded;
  std::lock_guard<std::mutex> lock(mutex);
  const std::string key = std::string(file) + '\n' + symbol;
  auto it = loaded.find(key);
  if (it == loaded.end()) {
    it = loaded.emplace(key, load(file, symbol, envVariable)).first;
  }
  error = it->second.error;
  return it->second.symbol;
}
} // namespace hslam
