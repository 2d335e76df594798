// Fuzz target: EuRoC cam0/data.csv, through vpHSlamImageSource::create.
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
  static const std::string dir = hslam_fuzz::makeDir("euroc/mav0/cam0/data");
  static const std::string sensor =
      hslam_fuzz::writeText("euroc/mav0/cam0/sensor.yaml",
                            "sensor_type: camera\n"
                            "T_BS:\n  cols: 4\n  rows: 4\n  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, "
                            "1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
                            "rate_hz: 20\nresolution: [752, 480]\ncamera_model: pinhole\n"
                            "intrinsics: [458.654, 457.296, 367.215, 248.375]\ndistortion_model: radial-tangential\n"
                            "distortion_coefficients: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n");
  hslam_fuzz::writeFile("euroc/mav0/cam0/data.csv", data, size);
  try {
    vpHSlamImageSource::Options options;
    options.format = vpHSlamImageSource::formatEuroc;
    vpHSlamImageSource::create(hslam_fuzz::scratchDir() + "/euroc", options);
  } catch (const vpHSlamException &) {
  }
  return 0;
}
