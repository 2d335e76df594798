// Module smoke test, run by ViSP's vp_add_tests (with "-c -d") both in a ViSP source build and stand-alone.
// It checks that the module's exported symbols link and that its error type keeps its code and message.
#include <visp3/hslam/vpHSlamException.h>

#include <iostream>

int main(int, char **)
{
  try {
    throw vpHSlamException(vpHSlamException::parseError, "camera.txt:2: expected 'width height'");
  } catch (const vpException &e) {
    if (e.getCode() != vpHSlamException::parseError || e.getStringMessage().find("camera.txt:2") == std::string::npos) {
      std::cerr << "vpHSlamException lost its code or message" << std::endl;
      return EXIT_FAILURE;
    }
  }
  std::cout << "visp_hslam module smoke test passed" << std::endl;
  return EXIT_SUCCESS;
}
