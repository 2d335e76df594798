// Test helpers: where the shared real sequences and ViSP's image data live, skipping cleanly when absent.
#ifndef HSLAM_TEST_DATA_H
#define HSLAM_TEST_DATA_H

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <sys/stat.h>

namespace hslam_test
{
inline bool pathExists(const std::string &path)
{
  struct stat st;
  return ::stat(path.c_str(), &st) == 0;
}

//! Folder of the shared sequences: $HSLAM_SHARED_DATA_DIR, else the build-time default (<repo>/../shared/data).
inline std::string sharedDataDir()
{
  const char *env = std::getenv("HSLAM_SHARED_DATA_DIR");
  return (env && *env) ? std::string(env) : std::string(HSLAM_SHARED_DATA_DIR_DEFAULT);
}

//! Path of a shared sequence (or file), empty when absent.
inline std::string sharedData(const std::string &relative)
{
  const std::string path = sharedDataDir() + "/" + relative;
  return pathExists(path) ? path : std::string();
}

//! ViSP's image data (Debian package visp-images-data), empty when absent.
inline std::string vispImagesDir()
{
  const char *env = std::getenv("VISP_INPUT_IMAGE_PATH");
  if (env && *env && pathExists(std::string(env) + "/ViSP-images")) {
    return std::string(env) + "/ViSP-images";
  }
  const std::string debian = "/usr/share/visp-images-data/ViSP-images";
  return pathExists(debian) ? debian : std::string();
}
} // namespace hslam_test

//! Declares `const std::string var` holding the path of a shared sequence, or skips the test with a message.
#define HSLAM_REQUIRE_SHARED_DATA(var, relative)                                                                       \
  const std::string var = hslam_test::sharedData(relative);                                                            \
  if (var.empty()) {                                                                                                   \
    GTEST_SKIP() << "shared data '" << relative << "' not found under " << hslam_test::sharedDataDir()                 \
                 << " (set HSLAM_SHARED_DATA_DIR to run this test)";                                                   \
  }

#endif
