// Fuzz target: KITTI times.txt, through vpHSlamImageSource::create.
// Contract checked: any input either parses or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageSource.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  static const std::string dir = hslam_fuzz::makeDir("kitti");
  static const std::string images = hslam_fuzz::makeDir("kitti/image_0");
  static const std::string calib =
      hslam_fuzz::writeText("kitti/calib.txt", "P0: 7.07e+02 0 6.01e+02 0 0 7.07e+02 1.83e+02 0 0 0 1 0\n");
  hslam_fuzz::writeFile("kitti/times.txt", data, size);
  try {
    vpHSlamImageSource::Options options;
    options.format = vpHSlamImageSource::formatKitti;
    vpHSlamImageSource::create(dir, options);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
