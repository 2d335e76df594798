#include "dataset/DatasetGroundTruth.h"

#include <visp3/hslam/vpHSlamException.h>
#include <visp3/hslam/vpHSlamTrajectoryEvaluator.h>

#include <filesystem>
#include <map>

namespace hslam_dataset
{
std::string groundTruthInput(const Arguments &args)
{
  if (args.groundTruthOut.empty()) {
    return std::string();
  }
  if (!args.groundTruth.empty()) {
    return args.groundTruth;
  }
  std::error_code ignored;
  const std::filesystem::path beside = std::filesystem::path(args.input) / "groundtruth.txt";
  if (std::filesystem::is_directory(args.input, ignored) && std::filesystem::is_regular_file(beside, ignored)) {
    return beside.string();
  }
  throw vpHSlamException(vpHSlamException::fileNotFound,
                         "--groundtruth-out: no ground truth found (no groundtruth.txt in '" + args.input +
                             "'); name one with --groundtruth FILE (TUM format)");
}

vpHSlamTrajectory groundTruthOfFedFrames(const vpHSlamTrajectory &groundTruth, const std::vector<FedStamp> &fed,
                                         double maxDt)
{
  // The way there as an "estimate" on the source's clock: associated as tutorial-hslam-evaluate would.
  vpHSlamTrajectory there;
  std::vector<unsigned int> thereIndex;
  for (const FedStamp &f : fed) {
    if (!f.backward) {
      there.add(f.sourceTimestamp, vpHomogeneousMatrix());
      thereIndex.push_back(f.index);
    }
  }
  const vpHSlamTrajectoryEvaluator association(groundTruth, there, maxDt);
  std::map<unsigned int, std::size_t> groundTruthOfIndex; // source index -> ground-truth pose
  for (const std::pair<std::size_t, std::size_t> &match : association.getMatches()) {
    groundTruthOfIndex[thereIndex[match.first]] = match.second;
  }
  vpHSlamTrajectory out;
  for (const FedStamp &f : fed) {
    const auto found = groundTruthOfIndex.find(f.index);
    if (found != groundTruthOfIndex.end()) {
      out.add(f.timestamp, groundTruth.get_wMc(found->second));
    }
  }
  return out;
}
} // namespace hslam_dataset
