// The tag room of test_system_tag (TagRoom.h) as a program, for tutorials/hslam-tag-benchmark.sh: one run of the
// three systems with the given point budget and mode, deterministic, printed as one line of key=value pairs per
// system (variant both, first-lap, none).
//
//   hslam_tag_room [--budget 500] [--mode slam] [--real-time] [--debug]
//
// Output per variant: metric, sightings, kept, scale_error (|s - 1| of the Sim(3) alignment onto the truth),
// frame_offset_m, frame_deg, ate_unaligned_m (no alignment), ate_sim3_m, tracked, loops, tag_ms (detection per
// keyframe), tracking_ms_median.
#include "TagRoom.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamLog.h>

#include <cstdlib>
#include <iostream>
#include <string>

int main(int argc, char **argv)
{
  int budget = 0;
  std::string mode;
  bool realTime = false;
  for (int k = 1; k < argc; ++k) {
    const std::string arg = argv[k];
    if (arg == "--budget" && k + 1 < argc) {
      budget = std::atoi(argv[++k]);
    } else if (arg == "--mode" && k + 1 < argc) {
      mode = argv[++k];
    } else if (arg == "--real-time") {
      realTime = true;
    } else if (arg == "--debug") {
      vpHSlamLog::setSink(vpHSlamLog::stderrSink());
      vpHSlamLog::setLevel(vpHSlamLog::debug);
    } else {
      std::cerr << "usage: " << argv[0]
                << " [--budget POINTS] [--mode vo-strict|vo-reuse|slam] [--real-time] [--debug]\n";
      return EXIT_FAILURE;
    }
  }
  if (hslam_test::vispImagesDir().empty() || !hslam_test::canDrawTags()) {
    std::cerr << "needs visp-images-data (textures) and libapriltag-dev at build time (the tag's image)\n";
    return EXIT_FAILURE;
  }
  try {
    vpHSlamParameters params;
    params.system.deterministic = !realTime; // real time: mapping and loop closure on their threads
    if (budget > 0) {
      params.features.desiredImmatureDensity = budget;
    }
    if (!mode.empty()) {
      params.system.mode = vpHSlamParameters::parseMode(mode);
    }
    const hslam_test::TagRoomRuns r = hslam_test::runTagRoom(params);
    const std::pair<const char *, const hslam_test::TagRoomRun *> runs[] = {
        {"both", &r.bothLaps}, {"first-lap", &r.firstLapOnly}, {"none", &r.noTag}};
    for (const auto &run : runs) {
      const vpHSlam::Statistics &s = run.second->statistics;
      const hslam_test::TagFrameError &e = run.second->error;
      std::cout << "variant=" << run.first << " mode=" << vpHSlamParameters::modeName(params.system.mode)
                << " budget=" << params.features.desiredImmatureDensity << " metric=" << (s.metric ? 1 : 0)
                << " sightings=" << s.tagSightings << " kept=" << s.tagSightingsUsed << " scale_error=" << e.scale
                << " frame_offset_m=" << e.metres << " frame_deg=" << e.degrees << " ate_unaligned_m=" << e.ateUnaligned
                << " ate_sim3_m=" << e.ateSim3 << " tracked=" << s.trackedFrames << " loops=" << s.loopsCorrected
                << " tag_corrections=" << s.tagCorrections << " tag_ms=" << s.tagDetectionMsMean
                << " tracking_ms_median=" << s.trackingMsMedian << std::endl;
    }
  } catch (const vpException &e) {
    std::cerr << "error: " << e.getStringMessage() << std::endl;
    return EXIT_FAILURE;
  }
  return EXIT_SUCCESS;
}
