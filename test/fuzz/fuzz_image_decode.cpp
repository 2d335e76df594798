// Fuzz target: the module's image decoder (io/ImageCodec.h: JPEG through libjpeg, PNG through libpng, PGM/PPM),
// which reads every dataset frame, at both depths.
// Contract checked: any input either decodes or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include "io/ImageCodec.h"

#include <visp3/hslam/vpHSlamException.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  try {
    vpImage<unsigned char> I;
    hslam::io::decodeGrey8(data, size, "fuzz", I);
  } catch (const vpHSlamException &) {
  }
  try {
    std::vector<std::uint16_t> samples;
    unsigned int w = 0, h = 0;
    int depth = 0;
    hslam::io::decodeGreyAnyDepth(data, size, "fuzz", samples, w, h, depth);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
