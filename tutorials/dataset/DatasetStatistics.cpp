#include "dataset/DatasetStatistics.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <cmath>
#include <csignal>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <sys/resource.h>

namespace hslam_dataset
{
namespace
{
std::string jsonNumber(double x)
{
  if (!std::isfinite(x)) {
    return "null";
  }
  std::ostringstream s;
  s << std::setprecision(10) << x;
  return s.str();
}

//! \e text as a JSON string, quotes included (a line break becomes a space: the messages are one line).
std::string jsonString(const std::string &text)
{
  std::string quoted = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') {
      quoted += '\\';
    }
    quoted += (c == '\n' ? ' ' : c);
  }
  return quoted + "\"";
}
//! The loop-closure and metric-frame (--tag) fields of writeStats(), each line ending with a comma.
void writeLoopAndTagFields(std::ostream &out, const vpHSlam::Statistics &s, const Arguments &args)
{
  out << "  \"loop_candidates_verified\": " << s.loopCandidatesVerified << ",\n"
      << "  \"loops_detected\": " << s.loopsDetected << ",\n"
      << "  \"loops_corrected\": " << s.loopsCorrected << ",\n"
      << "  \"last_loop_correction_ms\": " << jsonNumber(s.lastLoopCorrectionMs) << ",\n"
      << "  \"loop_correction_ms_max\": " << jsonNumber(s.loopCorrectionMsMax) << ",\n"
      << "  \"loop_detection_ms_mean\": " << jsonNumber(s.loopDetectionMsMean) << ",\n"
      << "  \"loop_verification_ms_max\": " << jsonNumber(s.loopVerificationMsMax) << ",\n"
      << "  \"loop_verification_ms_mean\": " << jsonNumber(s.loopVerificationMsMean) << ",\n"
      << "  \"global_ba_started\": " << s.globalBundleAdjustments << ",\n"
      << "  \"global_ba_applied\": " << s.globalBundleAdjustmentsApplied << ",\n"
      << "  \"global_ba_s_max\": " << jsonNumber(s.globalBundleAdjustmentSecondsMax) << ",\n"
      << "  \"global_ba_rms_before_px\": " << jsonNumber(s.globalBundleAdjustmentRmsBeforePx) << ",\n"
      << "  \"global_ba_rms_after_px\": " << jsonNumber(s.globalBundleAdjustmentRmsAfterPx) << ",\n"
      << "  \"frames_during_loop_correction\": " << s.framesDuringLoopCorrection << ",\n"
      << "  \"tracking_ms_max_during_loop_correction\": " << jsonNumber(s.trackingMsMaxDuringLoopCorrection) << ",\n"
      << "  \"tag\": " << (args.tag.isSet() ? jsonString(args.tag.toString()) : std::string("null")) << ",\n"
      << "  \"metric\": " << (s.metric ? "true" : "false") << ",\n"
      << "  \"tag_sightings\": " << s.tagSightings << ",\n"
      << "  \"tag_sightings_used\": " << s.tagSightingsUsed << ",\n"
      << "  \"tag_corrections\": " << s.tagCorrections << ",\n"
      << "  \"metric_scale\": " << jsonNumber(s.metricScale) << ",\n"
      << "  \"metric_scale_uncertainty\": " << jsonNumber(s.metricScaleUncertainty) << ",\n"
      << "  \"tag_detection_ms_mean\": " << jsonNumber(s.tagDetectionMsMean) << ",\n";
}
} // namespace

std::string signalName(int signal)
{
  switch (signal) {
  case SIGINT:
    return "SIGINT";
  case SIGTERM:
    return "SIGTERM";
  case SIGHUP:
    return "SIGHUP";
  default:
    return "signal " + std::to_string(signal);
  }
}

double peakRssMb()
{
  std::ifstream status("/proc/self/status");
  std::string line;
  while (std::getline(status, line)) {
    if (line.compare(0, 6, "VmHWM:") == 0) {
      std::istringstream in(line.substr(6));
      double kb = 0.;
      if (in >> kb) {
        return kb / 1024.;
      }
    }
  }
  return 0.;
}

double processCpuSeconds()
{
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) {
    return 0.;
  }
  constexpr double kMicro = 1e-6;
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         kMicro * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

void writeStats(const std::string &path, const vpHSlam::Statistics &s, const Arguments &args,
                const vpHSlamParameters &params, const RunOutcome &outcome)
{
  const double wallS = outcome.wallS, cpuS = outcome.cpuS, videoS = outcome.videoS;
  std::ofstream out(path.c_str());
  if (!out) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot write the statistics file '" + path + "'");
  }
  const unsigned int held = std::max(1u, s.keyframesHeld);
  out << "{\n"
      << "  \"input\": " << jsonString(args.input) << ",\n"
      << "  \"deterministic\": " << (params.system.deterministic ? "true" : "false") << ",\n"
      << "  \"mode\": " << jsonString(vpHSlamParameters::modeName(params.system.mode)) << ",\n"
      << "  \"tracking_mode\": " << jsonString(vpHSlamParameters::trackingModeName(params.tracking.mode)) << ",\n"
      << "  \"stride\": " << args.stride << ",\n"
      << "  \"blackout\": " << jsonString(args.blackoutText()) << ",\n"
      << "  \"there_and_back\": " << (args.thereAndBack ? "true" : "false") << ",\n"
      << "  \"backward_frames\": " << outcome.backwardFrames << ",\n"
      << "  \"frames\": " << s.frames << ",\n"
      << "  \"frames_read\": " << outcome.framesRead << ",\n"
      << "  \"blacked_out_frames\": " << outcome.blackedOutFrames << ",\n"
      << "  \"dropped_frames\": " << outcome.droppedFrames << ",\n"
      << "  \"tracked_frames\": " << s.trackedFrames << ",\n"
      << "  \"tracked_share\": " << jsonNumber(s.frames ? double(s.trackedFrames) / s.frames : 0.) << ",\n"
      << "  \"lost_frames\": " << s.lostFrames << ",\n"
      << "  \"segments\": " << s.segments << ",\n"
      << "  \"keyframes\": " << s.keyframes << ",\n"
      << "  \"mapping_skipped_frames\": " << s.mappingSkippedFrames << ",\n"
      << "  \"tracking_ms_median\": " << jsonNumber(s.trackingMsMedian) << ",\n"
      << "  \"tracking_ms_p95\": " << jsonNumber(s.trackingMsP95) << ",\n"
      << "  \"tracking_ms_max\": " << jsonNumber(s.trackingMsMax) << ",\n"
      << "  \"initialization_ms_median\": " << jsonNumber(s.initializationMsMedian) << ",\n"
      << "  \"mapping_ms_per_keyframe_median\": " << jsonNumber(s.mappingMsPerKeyframeMedian) << ",\n"
      << "  \"mapping_ms_per_keyframe_p95\": " << jsonNumber(s.mappingMsPerKeyframeP95) << ",\n"
      << "  \"mapping_ms_per_frame_median\": " << jsonNumber(s.mappingMsPerFrameMedian) << ",\n"
      << "  \"orb_matches_median\": " << jsonNumber(s.orbMatchesMedian) << ",\n"
      << "  \"orb_inliers_median\": " << jsonNumber(s.orbInliersMedian) << ",\n"
      << "  \"geometric_weight_median\": " << jsonNumber(s.geometricWeightMedian) << ",\n"
      << "  \"geometric_term_frames\": " << s.geometricTermFrames << ",\n"
      << "  \"geometric_term_share\": " << jsonNumber(s.geometricTermShare) << ",\n"
      << "  \"adaptive_large_motion_frames\": " << s.adaptiveLargeMotionFrames << ",\n"
      << "  \"adaptive_prediction_refused_frames\": " << s.adaptivePredictionRefusedFrames << ",\n"
      << "  \"adaptive_direct_failed_frames\": " << s.adaptiveDirectFailedFrames << ",\n"
      << "  \"relocalizations_attempted\": " << s.relocalizationsAttempted << ",\n"
      << "  \"relocalizations_succeeded\": " << s.relocalizationsSucceeded << ",\n"
      << "  \"active_points\": " << s.activePoints << ",\n"
      << "  \"peak_rss_mb\": " << jsonNumber(peakRssMb()) << ",\n"
      << "  \"map_memory_mb\": " << jsonNumber(s.mapMemoryMb) << ",\n"
      << "  \"memory_mb_per_keyframe\": " << jsonNumber(s.mapMemoryMbPerKeyframe) << ",\n"
      << "  \"window_memory_mb\": " << jsonNumber(s.mapMemoryMb - s.marginalizedMemoryMb) << ",\n"
      << "  \"marginalized_memory_mb\": " << jsonNumber(s.marginalizedMemoryMb) << ",\n"
      << "  \"keyframes_held\": " << held << ",\n"
      << "  \"marginalized_keyframes\": " << s.marginalizedKeyframes << ",\n"
      << "  \"culled_keyframes\": " << s.culledKeyframes << ",\n"
      << "  \"global_points\": " << s.globalPoints << ",\n"
      << "  \"reactivated_points_per_keyframe\": " << jsonNumber(s.reactivatedPointsPerKeyframe) << ",\n"
      << "  \"fused_points_per_keyframe\": " << jsonNumber(s.fusedPointsPerKeyframe) << ",\n"
      << "  \"window_share_from_global\": " << jsonNumber(s.windowShareFromGlobal) << ",\n"
      << "  \"descriptor_kb_per_keyframe\": " << jsonNumber(s.descriptorKbPerKeyframe) << ",\n";
  writeLoopAndTagFields(out, s, args);
  out << "  \"wall_s\": " << jsonNumber(wallS) << ",\n"
      << "  \"cpu_s\": " << jsonNumber(cpuS) << ",\n"
      << "  \"video_s\": " << jsonNumber(videoS) << ",\n"
      << "  \"realtime_factor\": " << jsonNumber(wallS > 0. ? videoS / wallS : 0.) << ",\n"
      << "  \"interrupted\": " << (outcome.signal != 0 ? "true" : "false") << ",\n"
      << "  \"signal\": " << (outcome.signal != 0 ? jsonString(signalName(outcome.signal)) : std::string("null"))
      << ",\n"
      << "  \"error\": " << (outcome.error.empty() ? std::string("null") : jsonString(outcome.error)) << "\n"
      << "}\n";
  out.flush();
  if (!out) {
    throw vpHSlamException(vpHSlamException::fileUnreadable, "cannot write the statistics file '" + path + "'");
  }
}
} // namespace hslam_dataset
