// Fuzz target: TUM RGB-D rgb.txt, through vpHSlamImageSource::create (list checks included).
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
  // A folder with a fixed camera.txt and the input as rgb.txt; the images it names do not exist (reported).
  static const std::string dir = hslam_fuzz::makeDir("tum-rgbd");
  static const std::string camera =
      hslam_fuzz::writeText("tum-rgbd/camera.txt", "Pinhole 500 500 319.5 239.5 0\n640 480\nnone\n640 480\n");
  hslam_fuzz::writeFile("tum-rgbd/rgb.txt", data, size);
  try {
    vpHSlamImageSource::Options options;
    options.format = vpHSlamImageSource::formatTumRgbd;
    vpHSlamImageSource::create(dir, options);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
