// Fuzz target: map files (vpHSlam::saveMap / loadMap format, read by hslam::loadMapFile).
// Contract checked: any input either loads or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). A corrupt count must not make the reader reserve memory it then
// cannot fill (-rss_limit_mb catches that). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include "features/OrbVocabulary.h"
#include "map/MapFile.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const std::string path = hslam_fuzz::writeFile("map.hmap", data, size);
  try {
    hslam::loadMapFile(path);
  } catch (const vpHSlamException &) {
  }
  // The checksum refuses almost every mutation before the records are read: the same input with its last 8 bytes
  // replaced by the right checksum reaches the record parser (counts, values, references).
  constexpr size_t kChecksumBytes = 8;
  if (size > kChecksumBytes) {
    std::string bytes(reinterpret_cast<const char *>(data), size);
    const size_t payload = size - kChecksumBytes;
    const std::uint64_t h = hslam::hashBytes(bytes.data(), payload);
    for (size_t b = 0; b < kChecksumBytes; ++b) {
      bytes[payload + b] = static_cast<char>((h >> (8 * b)) & 0xff);
    }
    try {
      hslam::parseMapFile(bytes, path);
    } catch (const vpHSlamException &) {
    }
  }
  return 0;
}
