//! \example tutorial-hslam-evaluate.cpp
//! Accuracy of an estimated trajectory against ground truth: ATE (after SE(3)/Sim(3) alignment), RPE, and
//! optionally the TUM monoVO alignment error, printed as machine-readable "key=value" lines; optional top-view plot.
//!
//!   ./tutorial-hslam-evaluate --groundtruth groundtruth.txt --estimate estimate.txt --align sim3 --plot top.png
#include <visp3/core/vpImage.h>
#include <visp3/core/vpIoTools.h>
#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamImageIo.h>
#include <visp3/hslam/vpHSlamTrajectory.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

namespace
{
struct Options {
  std::string groundTruth;
  std::string estimate;
  std::string format = "tum";
  std::string estimateFormat; // empty: tum, or kitti when the ground truth is kitti
  std::string sensorYaml;
  std::string groundTruthTimes;
  std::string estimateTimes;
  std::string align = "sim3";
  std::string plot;
  double maxDt = 0.02;
  double rpeDelta = 1.;
  double rpeDistance = 0.;
  double segmentLength = 0.;
  double from = -HUGE_VAL; // estimate poses before this time (s) are left out
  double to = HUGE_VAL;    // and after this one
};

void printUsage(const char *program)
{
  std::cout
      << "Usage: " << program << " --groundtruth GT --estimate EST [options]\n"
      << "Compares an estimated camera trajectory with ground truth and prints key=value lines:\n"
      << "  matched, ate_rmse_m, ate_mean_m, ate_median_m, ate_max_m, ate_std_m, scale, rpe_pairs, rpe_trans_rmse_m,\n"
      << "  rpe_rot_rmse_deg (and alignment_error_m, drift_* with --segment-length).\n\n"
      << "Options:\n"
      << "  --groundtruth FILE     ground-truth trajectory (camera-to-world poses)\n"
      << "  --estimate FILE        estimated trajectory (TUM format unless --estimate-format)\n"
      << "  --format F             ground-truth format: tum (default), kitti or euroc "
         "(state_groundtruth_estimate0/data.csv)\n"
      << "  --estimate-format F    tum or kitti (default: kitti when --format kitti, else tum)\n"
      << "  --sensor-yaml FILE     EuRoC cam0 sensor.yaml: T_BS turns body poses into camera poses\n"
      << "                         (default for euroc: <csv folder>/../cam0/sensor.yaml when it exists)\n"
      << "  --times FILE           KITTI ground-truth times file (else timestamps are row indices)\n"
      << "  --estimate-times FILE  KITTI estimate times file\n"
      << "  --align A              sim3 (default, monocular), se3 or none\n"
      << "  --max-dt S             largest time difference of an associated pair, seconds (default 0.02)\n"
      << "  --rpe-delta S          RPE over S seconds (default 1)\n"
      << "  --rpe-distance M       RPE over M metres of ground-truth path instead of time\n"
      << "  --segment-length S     also print the TUM monoVO alignment error with start/end segments of S seconds\n"
      << "  --from S / --to S      evaluate only the estimate's poses from / up to timestamp S, seconds as in the\n"
      << "                         file (e.g. only the frames another system tracked too; default: every pose)\n"
      << "  --plot FILE.png        write a top view of ground truth and aligned estimate\n"
      << "  --help                 this text\n";
}

//! Parse a strictly positive (or non-negative) number, or explain.
bool parseNumber(const std::string &name, const std::string &text, double &value, bool allowZero)
{
  char *end = nullptr;
  value = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(value) || value < 0. || (!allowZero && value == 0.)) {
    std::cerr << "error: " << name << " expects a " << (allowZero ? "non-negative" : "positive") << " number, got '"
              << text << "'" << std::endl;
    return false;
  }
  return true;
}

//! 0: go on, 1: error, 2: help printed.
int parseArguments(int argc, char **argv, Options &options)
{
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      printUsage(argv[0]);
      return 2;
    }
    if (arg == "-c" || arg == "-d") {
      continue; // ViSP test-runner flags (no click, no display): nothing to do here
    }
    if (i + 1 >= argc) {
      std::cerr << "error: unknown option or missing value: " << arg << " (see --help)" << std::endl;
      return 1;
    }
    const std::string value = argv[++i];
    bool ok = true;
    if (arg == "--groundtruth") {
      options.groundTruth = value;
    } else if (arg == "--estimate") {
      options.estimate = value;
    } else if (arg == "--format") {
      options.format = value;
    } else if (arg == "--estimate-format") {
      options.estimateFormat = value;
    } else if (arg == "--sensor-yaml") {
      options.sensorYaml = value;
    } else if (arg == "--times") {
      options.groundTruthTimes = value;
    } else if (arg == "--estimate-times") {
      options.estimateTimes = value;
    } else if (arg == "--align") {
      options.align = value;
    } else if (arg == "--plot") {
      options.plot = value;
    } else if (arg == "--max-dt") {
      ok = parseNumber(arg, value, options.maxDt, true);
    } else if (arg == "--rpe-delta") {
      ok = parseNumber(arg, value, options.rpeDelta, false);
    } else if (arg == "--rpe-distance") {
      ok = parseNumber(arg, value, options.rpeDistance, false);
    } else if (arg == "--segment-length") {
      ok = parseNumber(arg, value, options.segmentLength, false);
    } else if (arg == "--from") {
      ok = parseNumber(arg, value, options.from, true);
    } else if (arg == "--to") {
      ok = parseNumber(arg, value, options.to, true);
    } else {
      std::cerr << "error: unknown option " << arg << " (see --help)" << std::endl;
      return 1;
    }
    if (!ok) {
      return 1;
    }
  }
  if (options.groundTruth.empty() || options.estimate.empty()) {
    std::cerr << "error: --groundtruth and --estimate are required (see --help)" << std::endl;
    return 1;
  }
  if (options.from > options.to) {
    std::cerr << "error: --from " << options.from << " is after --to " << options.to << std::endl;
    return 1;
  }
  return 0;
}

vpHSlamTrajectory readGroundTruth(const Options &options)
{
  const vpHSlamTrajectory::Format format = vpHSlamTrajectory::formatFromString(options.format);
  if (format == vpHSlamTrajectory::formatKitti) {
    return vpHSlamTrajectory::readKitti(options.groundTruth, options.groundTruthTimes);
  }
  if (format == vpHSlamTrajectory::formatEuroc) {
    std::string yaml = options.sensorYaml;
    if (yaml.empty()) {
      const std::string guess = vpIoTools::getParent(vpIoTools::getParent(options.groundTruth)) + "/cam0/sensor.yaml";
      if (vpIoTools::checkFilename(guess)) {
        yaml = guess;
        std::cout << "# using T_BS from " << yaml << std::endl;
      } else {
        std::cout << "# no --sensor-yaml: comparing against the BODY (IMU) frame" << std::endl;
      }
    }
    return yaml.empty() ? vpHSlamTrajectory::readEurocGroundTruth(options.groundTruth)
                        : vpHSlamTrajectory::readEurocGroundTruth(options.groundTruth, yaml);
  }
  return vpHSlamTrajectory::readTum(options.groundTruth);
}

vpHSlamTrajectory readEstimate(const Options &options)
{
  std::string name = options.estimateFormat;
  if (name.empty()) {
    name = options.format == "kitti" ? "kitti" : "tum";
  }
  const vpHSlamTrajectory::Format format = vpHSlamTrajectory::formatFromString(name);
  if (format == vpHSlamTrajectory::formatKitti) {
    return vpHSlamTrajectory::readKitti(options.estimate, options.estimateTimes);
  }
  if (format != vpHSlamTrajectory::formatTum) {
    throw vpHSlamException(vpHSlamException::invalidArgument, "--estimate-format must be tum or kitti");
  }
  return vpHSlamTrajectory::readTum(options.estimate);
}

void printValue(const char *key, double value)
{
  std::printf("%s=%.6f\n", key, value);
}

//! The ground truth over the time span of the associated pairs (so the plot is not dominated by unmatched parts).
vpHSlamTrajectory groundTruthSpan(const vpHSlamTrajectory &groundTruth, const vpHSlamTrajectoryEvaluator &evaluator)
{
  const auto &matches = evaluator.getMatches();
  const double first = groundTruth.getTimestamp(matches.front().second);
  const double last = groundTruth.getTimestamp(matches.back().second);
  // Matches follow the estimate's order; two nearly simultaneous ones may meet the ground truth crosswise.
  return first <= last ? groundTruth.timeSpan(first, last) : vpHSlamTrajectory();
}

int run(const Options &options)
{
  const vpHSlamTrajectoryEvaluator::Alignment alignment =
      vpHSlamTrajectoryEvaluator::alignmentFromString(options.align);
  const vpHSlamTrajectory groundTruth = readGroundTruth(options);
  const vpHSlamTrajectory estimate = readEstimate(options).timeSpan(options.from, options.to);
  if (estimate.empty()) {
    std::cerr << "error: no estimated pose between --from " << options.from << " and --to " << options.to << " s"
              << std::endl;
    return EXIT_FAILURE;
  }
  const vpHSlamTrajectoryEvaluator evaluator(groundTruth, estimate, options.maxDt);

  std::printf("matched=%zu\n", evaluator.getMatchedCount());
  const vpHSlamTrajectoryEvaluator::AteResult ate = evaluator.computeAte(alignment);
  printValue("ate_rmse_m", ate.error.rmse);
  printValue("ate_mean_m", ate.error.mean);
  printValue("ate_median_m", ate.error.median);
  printValue("ate_max_m", ate.error.max);
  printValue("ate_std_m", ate.error.std);
  printValue("scale", ate.scale);

  const bool byDistance = options.rpeDistance > 0.;
  const vpHSlamTrajectoryEvaluator::RpeResult rpe =
      evaluator.computeRpe(byDistance ? options.rpeDistance : options.rpeDelta, byDistance, alignment);
  std::printf("rpe_pairs=%zu\n", rpe.translation.count);
  // No pair spans the delta: say so with nan rather than a misleading 0.
  printValue("rpe_trans_rmse_m", rpe.translation.count > 0 ? rpe.translation.rmse : NAN);
  printValue("rpe_rot_rmse_deg", rpe.rotationDeg.count > 0 ? rpe.rotationDeg.rmse : NAN);

  if (options.segmentLength > 0.) {
    const vpHSlamTrajectoryEvaluator::AlignmentErrorResult mono =
        evaluator.computeAlignmentError(options.segmentLength);
    printValue("alignment_error_m", mono.alignmentError);
    printValue("drift_translation_m", mono.translationDrift);
    printValue("drift_rotation_deg", mono.rotationDriftDeg);
    printValue("drift_scale", mono.scaleDrift);
  }
  std::fflush(stdout);

  if (!options.plot.empty()) {
    char caption[160];
    std::snprintf(caption, sizeof(caption), "ATE RMSE %.4f m (%s, scale %.4f), %zu poses", ate.error.rmse,
                  options.align.c_str(), ate.scale, ate.error.count);
    vpImage<vpRGBa> I;
    vpHSlamTrajectoryEvaluator::drawTopView(I, groundTruthSpan(groundTruth, evaluator),
                                            evaluator.getAlignedEstimate(ate), caption);
    vpHSlamImageIo::writePng(options.plot, I);
    std::cout << "# plot written to " << options.plot << std::endl;
  }
  return EXIT_SUCCESS;
}
} // namespace

int main(int argc, char **argv)
{
  Options options;
  const int parsed = parseArguments(argc, argv, options);
  if (parsed == 2) {
    return EXIT_SUCCESS;
  }
  if (parsed != 0) {
    return 2;
  }
  try {
    return run(options);
  } catch (const vpException &e) {
    std::cerr << "error: " << e.getStringMessage() << std::endl;
  } catch (const std::exception &e) {
    std::cerr << "error: " << e.what() << std::endl;
  }
  return EXIT_FAILURE;
}
