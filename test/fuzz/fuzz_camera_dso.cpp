// Fuzz target: DSO camera.txt (vpHSlamCamera::loadDso), every model and rectification line.
// Contract checked: any input either parses or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include <visp3/hslam/vpHSlamCamera.h>
#include <visp3/hslam/vpHSlamException.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const std::string path = hslam_fuzz::writeFile("camera.txt", data, size);
  try {
    vpHSlamCamera::loadDso(path);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
