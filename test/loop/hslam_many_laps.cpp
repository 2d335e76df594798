// Loop closure at scale, end to end (issue 50): the synthetic outward room driven lap after lap, rendered in memory
// at a small size, fed to one system in slam mode (deterministic, the defaults otherwise) until it has stored the
// asked number of keyframes. Every --report keyframes it prints one line: stored keyframes, the mean loop detection
// time per keyframe over that stretch (query, consistency, verification) and its verification part, the corrections
// applied so far and the last one's time with the map size it ran on, the process's peak resident memory, and the ATE
// (Sim(3)-aligned, metres) of every frame tracked so far against the room's truth. With --no-reuse the global map's
// re-use is off, so every revisit is reconciled by loop closure alone and corrections happen at every size.
// --log writes the library's info messages (each loop, its pose graph and correction time) to stderr.
//
//   hslam_many_laps [--keyframes 10000] [--width 320 --height 240] [--report 500] [--budget POINTS] [--no-reuse]
//                   [--max-laps 400] [--log]
//
// Labelled a benchmark: tens of minutes on a 2-core machine for 10,000 keyframes; not run by CI.
#include "../system/SystemTestUtils.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <cstdlib>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

namespace
{
//! Peak resident memory of the process, MB (VmHWM), or -1 when /proc is not there.
double peakResidentMb()
{
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return std::atof(line.c_str() + 6) / 1024.;
    }
  }
  return -1.;
}

struct Options {
  unsigned int keyframes = 10000, width = 320, height = 240, report = 500, budget = 0, maxLaps = 400;
  bool reuse = true;
};

bool parse(int argc, char **argv, Options &o)
{
  const std::map<std::string, unsigned int *> counts = {{"--keyframes", &o.keyframes}, {"--width", &o.width},
                                                        {"--height", &o.height},       {"--report", &o.report},
                                                        {"--budget", &o.budget},       {"--max-laps", &o.maxLaps}};
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    const auto count = counts.find(arg);
    if (count != counts.end()) { // a positive count
      const long v = k + 1 < argc ? std::atol(argv[++k]) : 0;
      if (v <= 0) {
        return false;
      }
      *count->second = static_cast<unsigned int>(v);
    } else if (arg == "--no-reuse") {
      o.reuse = false;
    } else if (arg == "--log") {
      vpHSlamLog::setSink(vpHSlamLog::stderrSink());
      vpHSlamLog::setLevel(vpHSlamLog::info);
    } else {
      return false;
    }
  }
  return true;
}
} // namespace

int main(int argc, char **argv)
{
  Options o;
  if (!parse(argc, argv, o)) {
    std::cerr << "usage: " << argv[0]
              << " [--keyframes N] [--width W --height H] [--report N] [--budget POINTS] [--no-reuse] [--max-laps N]"
                 " [--log]\n";
    return EXIT_FAILURE;
  }
  if (hslam_test::vispImagesDir().empty()) {
    std::cerr << "needs visp-images-data (the room's textures)\n";
    return EXIT_FAILURE;
  }
  try {
    constexpr unsigned int kFramesPerLap = 400; // the outward room's least (a full turn per lap)
    vpHSlamSyntheticScene scene;
    scene.setLaps(o.maxLaps);
    scene.setLookOutward(true);
    scene.configure(o.width, o.height, kFramesPerLap * o.maxLaps + 1, 30., 1);
    vpHSlamParameters params;
    params.system.deterministic = true;
    params.globalMap.reuse = o.reuse;
    if (o.budget > 0) {
      params.features.desiredImmatureDensity = static_cast<int>(o.budget);
    }
    vpHSlam slam(hslam_test::syntheticCamera(scene), params);
    std::cout << "# " << o.width << "x" << o.height << ", re-use " << (o.reuse ? "on" : "off") << ", budget "
              << params.features.desiredImmatureDensity << "\n"
              << "# frame stored_keyframes segments detection_ms_mean_since_last verification_ms_mean_since_last "
                 "corrections last_correction_ms last_correction_at_keyframes peak_rss_mb ate_m\n";
    vpImage<unsigned char> I;
    unsigned int nextReport = o.report, correctionsSeen = 0, correctionAt = 0;
    double detectionTotal = 0., verificationTotal = 0.;
    unsigned int detections = 0;
    vpHSlam::Statistics s;
    vpHSlamTrajectory truth; // the frames fed so far
    for (unsigned int i = 0; i < scene.getFrameCount(); ++i) {
      scene.render(i, I);
      slam.track(I, scene.getTimestamp(i));
      truth.add(scene.getTimestamp(i), scene.getPose(i));
      if (i % 50 != 0) {
        continue;
      }
      s = slam.getStatistics();
      if (s.loopsCorrected != correctionsSeen) {
        correctionsSeen = s.loopsCorrected;
        correctionAt = s.marginalizedKeyframes;
      }
      if (s.marginalizedKeyframes >= nextReport || s.marginalizedKeyframes >= o.keyframes) {
        const double total = s.loopDetectionMsMean * s.loopDetections;
        const double verification = s.loopVerificationMsMean * s.loopDetections;
        const unsigned int count = s.loopDetections - detections;
        std::cout << i << " " << s.marginalizedKeyframes << " " << s.segments << " "
                  << (count > 0 ? (total - detectionTotal) / count : 0.) << " "
                  << (count > 0 ? (verification - verificationTotal) / count : 0.) << " " << s.loopsCorrected << " "
                  << s.lastLoopCorrectionMs << " " << correctionAt << " " << peakResidentMb() << " "
                  << hslam_test::simAte(truth, slam.getTrajectory()) << std::endl;
        detectionTotal = total;
        verificationTotal = verification;
        detections = s.loopDetections;
        nextReport = s.marginalizedKeyframes + o.report;
      }
      if (s.marginalizedKeyframes >= o.keyframes) {
        break;
      }
    }
    slam.synchronize();
    s = slam.getStatistics();
    std::cout << "# end: " << s.marginalizedKeyframes << " stored keyframes, " << s.loopsCorrected
              << " corrections (longest " << s.loopCorrectionMsMax << " ms), loop detection " << s.loopDetectionMsMean
              << " ms per keyframe, tracking " << s.trackingMsMedian << " ms per frame (median), peak resident memory "
              << peakResidentMb() << " MB" << std::endl;
  } catch (const vpHSlamException &e) {
    std::cerr << "error: " << e.getStringMessage() << "\n";
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
