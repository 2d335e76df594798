// Fuzz target: vocabulary files read as yaml (vpHSlamVocabulary::load with formatDbow2Yaml).
// Contract checked: any input either loads or raises vpHSlamException; nothing else escapes, and no sanitizer
// report (memory, undefined behaviour, leak). Built with libFuzzer (clang, -DHSLAM_FUZZ=ON) or, with any compiler,
// as a replay of the seed and regression inputs (FuzzReplayMain.cpp).
#include "FuzzInput.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamVocabulary.h>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
  const std::string path = hslam_fuzz::writeFile("vocabulary.yml", data, size);
  try {
    vpHSlamVocabulary::load(path, vpHSlamVocabulary::formatDbow2Yaml);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
