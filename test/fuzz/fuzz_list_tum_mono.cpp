// Fuzz target: TUM monoVO times.txt (id, time, exposure), through vpHSlamImageSource::create.
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
  static const std::string dir = hslam_fuzz::makeDir("tum-mono");
  static const std::string images = hslam_fuzz::makeDir("tum-mono/images");
  static const std::string camera =
      hslam_fuzz::writeText("tum-mono/camera.txt", "Pinhole 500 500 319.5 239.5 0\n640 480\nnone\n640 480\n");
  hslam_fuzz::writeFile("tum-mono/times.txt", data, size);
  try {
    vpHSlamImageSource::Options options;
    options.format = vpHSlamImageSource::formatTumMono;
    vpHSlamImageSource::create(dir, options);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
