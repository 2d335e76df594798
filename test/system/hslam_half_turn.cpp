// The hand-held half turn of test_system_global_map (SystemTestUtils.h, runHalfTurn) as a program, for the
// adaptive-tracking benchmark (tutorials/hslam-adaptive-benchmark.sh): one run with the given pivot, tracking mode
// and point budget, deterministic, printed as one line of key=value pairs.
//
//   hslam_half_turn --pivot 0.3 [--tracking-mode adaptive] [--budget 500] [--motion-px PX] [--save PREFIX]
//   [--debug]
//
// Output: pivot, mode, budget, frames, tracked, lost, segments, ate (Sim(3)-aligned, metres, every frame fed),
// tracking_ms_median and geometric_share (frames whose pose used the geometric term, over the frames tracked).
#include "SystemTestUtils.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <cstdlib>
#include <iostream>
#include <string>

int main(int argc, char **argv)
{
  double pivot = 0.;
  std::string mode;
  int budget = 0;
  double motionPx = 0.; //!< tracking.adaptiveMotionPx, 0: the default
  std::string save;     //!< prefix of the trajectory and ground-truth files (TUM), none when empty
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "--pivot" && k + 1 < argc) {
      pivot = std::atof(argv[++k]);
    } else if (arg == "--tracking-mode" && k + 1 < argc) {
      mode = argv[++k];
    } else if (arg == "--save" && k + 1 < argc) {
      save = argv[++k];
    } else if (arg == "--motion-px" && k + 1 < argc) {
      motionPx = std::atof(argv[++k]);
    } else if (arg == "--debug") {
      vpHSlamLog::setSink(vpHSlamLog::stderrSink());
      vpHSlamLog::setLevel(vpHSlamLog::debug);
    } else if (arg == "--budget" && k + 1 < argc) {
      budget = std::atoi(argv[++k]);
    } else {
      std::cerr << "usage: " << argv[0]
                << " --pivot METRES [--tracking-mode MODE] [--budget POINTS] [--motion-px PX] [--save PREFIX]"
                   " [--debug]\n";
      return EXIT_FAILURE;
    }
  }
  if (hslam_test::vispImagesDir().empty()) {
    std::cerr << "ViSP image data (visp-images-data) not found: no texture for the synthetic scene\n";
    return EXIT_FAILURE;
  }
  try {
    vpHSlamParameters params;
    params.system.deterministic = true;
    if (!mode.empty()) {
      params.tracking.mode = vpHSlamParameters::parseTrackingMode(mode);
    }
    if (motionPx > 0.) {
      params.tracking.adaptiveMotionPx = motionPx;
    }
    if (budget > 0) {
      params.features.desiredImmatureDensity = budget;
    }
    const hslam_test::HalfTurnRun r = hslam_test::runHalfTurn(params, pivot);
    if (!save.empty()) {
      r.run.trajectory.saveTum(save + ".trajectory.txt");
      r.groundTruth.saveTum(save + ".groundtruth.txt");
    }
    const vpHSlam::Statistics &s = r.run.statistics;
    std::cout << "pivot=" << pivot << " mode=" << vpHSlamParameters::trackingModeName(params.tracking.mode)
              << " budget=" << params.features.desiredImmatureDensity << " frames=" << s.frames
              << " tracked=" << s.trackedFrames << " lost=" << s.lostFrames << " segments=" << s.segments
              << " ate=" << hslam_test::simAte(r.groundTruth, r.run.trajectory)
              << " tracking_ms_median=" << s.trackingMsMedian << " geometric_share=" << s.geometricTermShare
              << std::endl;
  } catch (const vpException &e) {
    std::cerr << "error: " << e.getStringMessage() << std::endl;
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
