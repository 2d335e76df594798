// Fuzz target: map files (vpHSlam::saveMap / loadMap format, read by hslam::loadMapFile).
// Contract checked: any input either loads or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). A corrupt count must not make the reader reserve memory it then
// cannot fill (-rss_limit_mb catches that). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include "map/MapFile.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const std::string path = hslam_fuzz::writeFile("map.hmap", data, size);
  try {
    hslam::loadMapFile(path);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
