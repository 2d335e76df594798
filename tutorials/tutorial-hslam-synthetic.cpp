//! \example tutorial-hslam-synthetic.cpp
//! Render a synthetic sequence of a textured room with exact ground truth, in the TUM RGB-D layout.
//!
//!   tutorial-hslam-synthetic --output /tmp/synthetic [--frames 300] [--laps 1] [--seed 1] [--width 640 --height 480]
//!                            [--vignette] [--response] [--exposure-changes] [--noise 2] [--motion-blur]
#include <visp3/core/vpTime.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <cstdlib>
#include <iostream>
#include <string>

namespace
{
void usage(const char *program)
{
  std::cout << "Usage: " << program
            << " --output DIR [--frames N] [--laps N] [--look-outward] [--seed S] [--width W --height H] [--fps F]\n"
               "       [--vignette] [--response] [--exposure-changes] [--noise SIGMA] [--motion-blur] [--help]\n\n"
               "Renders a textured room (photographs from visp-images-data) seen by a hand-held-like camera\n"
               "that loops back to its start, and writes DIR/rgb/NNNNNN.png, rgb.txt, groundtruth.txt (wMc, TUM),\n"
               "camera.txt (DSO), camera.xml (ViSP), times.txt (id time exposure_ms), and with the photometric\n"
               "options vignette.png and pcalib.txt. Same options and seed: byte-identical output.\n\n"
               "  --output DIR        folder to write (created)\n"
               "  --frames N          frame count, default 300 (the last frame has the pose of the first)\n"
               "  --seed S            trajectory phases and noise, default 1\n"
               "  --laps N            drive the loop N times (default 1; N should divide frames - 1)\n"
               "  --look-outward      film the walls in turn, a full turn per lap (needs 400 frames a lap or more)\n"
               "  --width W           image width, default 640\n"
               "  --height H          image height, default 480\n"
               "  --fps F             frame rate, default 30\n"
               "  --vignette          radial vignette (50 % in the corners), writes vignette.png\n"
               "  --response          gamma camera response, writes its inverse as pcalib.txt\n"
               "  --exposure-changes  smoothly varying exposure time (in times.txt)\n"
               "  --noise SIGMA       additive Gaussian noise, grey levels\n"
               "  --motion-blur       average sub-frame renders over the exposure time\n";
}

bool parseUnsigned(const std::string &text, unsigned int &value)
{
  char *end = nullptr;
  const unsigned long v = std::strtoul(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0') {
    return false;
  }
  value = static_cast<unsigned int>(v);
  return true;
}

bool parseDouble(const std::string &text, double &value)
{
  char *end = nullptr;
  value = std::strtod(text.c_str(), &end);
  return end != text.c_str() && *end == '\0';
}
} // namespace

int main(int argc, char **argv)
{
  std::string output;
  unsigned int frames = 300, seed = 1, width = 640, height = 480, laps = 1;
  bool lookOutward = false;
  double fps = 30.0;
  vpHSlamSyntheticScene::Effects effects;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const bool hasValue = k + 1 < argc;
    bool ok = true;
    if (arg == "--help" || arg == "-h") {
      usage(argv[0]);
      return EXIT_SUCCESS;
    } else if (arg == "--output" && hasValue) {
      output = argv[++k];
    } else if (arg == "--frames" && hasValue) {
      ok = parseUnsigned(argv[++k], frames);
    } else if (arg == "--laps" && hasValue) {
      ok = parseUnsigned(argv[++k], laps) && laps > 0;
    } else if (arg == "--look-outward") {
      lookOutward = true;
    } else if (arg == "--seed" && hasValue) {
      ok = parseUnsigned(argv[++k], seed);
    } else if (arg == "--width" && hasValue) {
      ok = parseUnsigned(argv[++k], width);
    } else if (arg == "--height" && hasValue) {
      ok = parseUnsigned(argv[++k], height);
    } else if (arg == "--fps" && hasValue) {
      ok = parseDouble(argv[++k], fps);
    } else if (arg == "--noise" && hasValue) {
      ok = parseDouble(argv[++k], effects.noiseSigma);
    } else if (arg == "--vignette") {
      effects.vignette = true;
    } else if (arg == "--response") {
      effects.response = true;
    } else if (arg == "--exposure-changes") {
      effects.exposureChanges = true;
    } else if (arg == "--motion-blur") {
      effects.motionBlur = true;
    } else {
      std::cerr << "Unknown or incomplete option '" << arg << "'\n\n";
      usage(argv[0]);
      return EXIT_FAILURE;
    }
    if (!ok) {
      std::cerr << "Bad value for " << arg << ": '" << argv[k] << "'\n";
      return EXIT_FAILURE;
    }
  }
  if (output.empty()) {
    std::cerr << "Missing --output DIR\n\n";
    usage(argv[0]);
    return EXIT_FAILURE;
  }

  try {
    vpHSlamSyntheticScene scene;
    scene.setLaps(laps);
    scene.setLookOutward(lookOutward);
    scene.configure(width, height, frames, fps, seed, effects);
    std::cout << "Synthetic room: " << width << "x" << height << ", " << frames << " frames at " << fps << " Hz, seed "
              << seed << "\nTextures:\n";
    for (const std::string &file : scene.getTextureFiles()) {
      std::cout << "  " << file << "\n";
    }
    const double t0 = vpTime::measureTimeMs();
    scene.writeSequence(output);
    const double elapsedS = (vpTime::measureTimeMs() - t0) * 1e-3;
    std::cout << "Wrote " << frames << " frames to " << output << " in " << elapsedS << " s ("
              << 1e3 * elapsedS / frames << " ms per frame)\n"
              << "Play it back for example with: tutorial-hslam-dataset --input " << output << "\n";
  } catch (const vpException &e) {
    std::cerr << "Error: " << e.getStringMessage() << std::endl;
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
