// Fuzz target: KITTI poses files (vpHSlamTrajectory::readKitti, without and with times.txt).
// Contract checked: any input either parses or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const std::string path = hslam_fuzz::writeFile("poses.txt", data, size);
  try {
    vpHSlamTrajectory::readKitti(path, "", 10.);
  } catch (const vpHSlamException &) {
  }
  // The same bytes as times.txt of a fixed 3-pose file.
  static const std::string poses = hslam_fuzz::writeText("poses3.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n"
                                                                       "1 0 0 1 0 1 0 0 0 0 1 0\n"
                                                                       "1 0 0 2 0 1 0 0 0 0 1 0\n");
  try {
    vpHSlamTrajectory::readKitti(poses, path);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
