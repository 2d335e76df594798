// Fuzz target: the parameters YAML (vpHSlamParameters::load, then validate).
// Contract checked: any input either parses or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const std::string path = hslam_fuzz::writeFile("parameters.yaml", data, size);
  try {
    vpHSlamParameters params;
    params.load(path);
    params.validate();
  } catch (const vpHSlamException &) {
  }
  return 0;
}
