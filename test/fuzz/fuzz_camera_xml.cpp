// Fuzz target: ViSP camera XML (vpHSlamCamera::loadViSPXml, through vpXmlParserCamera).
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
  const std::string path = hslam_fuzz::writeFile("camera.xml", data, size);
  try {
    vpHSlamCamera::loadViSPXml(path);
  } catch (const vpHSlamException &) {
  }
  try {
    vpHSlamCamera::loadViSPXml(path, "Camera", 640, 480); // a named camera, size given
  } catch (const vpHSlamException &) {
  }
  return 0;
}
