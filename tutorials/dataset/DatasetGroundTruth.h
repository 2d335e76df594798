// --groundtruth-out of tutorial-hslam-dataset: the ground truth of the frames given to tracking, under the stamps they
// were tracked with, so an estimate of a re-timed run (--there-and-back) is evaluated by tutorial-hslam-evaluate as
// it is, with no option.
#ifndef HSLAM_TUTORIAL_DATASET_GROUND_TRUTH_H
#define HSLAM_TUTORIAL_DATASET_GROUND_TRUTH_H

#include "dataset/DatasetArguments.h"
#include "dataset/DatasetPlayback.h"

#include <visp3/hslam/vpHSlamTrajectory.h>

#include <string>
#include <vector>

namespace hslam_dataset
{
/*!
  The ground-truth file --groundtruth-out is made from: --groundtruth FILE, else groundtruth.txt in the --input
  folder (TUM RGB-D layout); empty without --groundtruth-out.
  \exception vpHSlamException::fileNotFound with --groundtruth-out when there is none (before the run, not after).
*/
std::string groundTruthInput(const Arguments &args);

/*!
  The ground truth of the frames given to tracking, in their order, each under the stamp it was tracked with.

  Each frame of the way there is associated by its source stamp with a ground-truth stamp exactly as
  tutorial-hslam-evaluate associates an estimate (vpHSlamTrajectoryEvaluator: nearest within \e maxDt, one to one),
  so the way there gets the poses a plain run would be compared with. A frame of the way back (FedStamp::backward)
  shows a frame of the way there (same source index) and gets its pose, under its re-timed stamp. This holds
  whatever the ground-truth rate (TUM RGB-D's ground truth is not at the image times): no stamp is mirrored or
  interpolated, each frame's pose is looked up through its source frame. A frame without a ground-truth stamp
  within \e maxDt has no pose in the result (as it would have no pair in the evaluation).

  \param groundTruth : camera-to-world poses stamped on the source's clock.
  \param fed : FramePlayback::getFedStamps().
*/
vpHSlamTrajectory groundTruthOfFedFrames(const vpHSlamTrajectory &groundTruth, const std::vector<FedStamp> &fed,
                                         double maxDt = kGroundTruthMaxDt);
} // namespace hslam_dataset

#endif
