// Fuzz target: TUM monoVO pcalib.txt, the inverse camera response (vpHSlamPhotometricCalibration::load).
// Contract checked: any input either parses or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamPhotometricCalibration.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const std::string path = hslam_fuzz::writeFile("pcalib.txt", data, size);
  try {
    vpHSlamPhotometricCalibration calibration;
    calibration.load(path, "", 64, 48);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
