// Statistics of a tutorial-hslam-dataset run: how it ended, what it cost (time, memory), and the JSON file of
// --stats that the benchmark scripts and the tests read.
#ifndef HSLAM_TUTORIAL_DATASET_STATISTICS_H
#define HSLAM_TUTORIAL_DATASET_STATISTICS_H

#include "dataset/DatasetArguments.h"

#include <visp3/hslam/vpHSlam.h>

#include <string>

namespace hslam_dataset
{
//! How a run ended, besides what vpHSlam::Statistics says.
struct RunOutcome {
  double wallS = 0.;                 //!< wall-clock time of the frame loop, seconds
  double cpuS = 0.;                  //!< CPU time (user + system, all threads) of the frame loop, seconds
  double videoS = 0.;                //!< duration of the frames read, by their timestamps, and of the way back, s
  unsigned int framesRead = 0;       //!< frames read from the source (fed to tracking or skipped by --stride)
  unsigned int blackedOutFrames = 0; //!< frames fed to tracking as a black image (--blackout), both ways
  unsigned int backwardFrames = 0;   //!< frames fed to tracking on the way back (--there-and-back)
  unsigned int droppedFrames = 0;    //!< unreadable frames skipped (--skip-unreadable)
  int signal = 0;                    //!< termination signal that stopped the run, 0 when none
  std::string error;                 //!< error that stopped the run, empty when none
};

//! "SIGINT", "SIGTERM", "SIGHUP", else "signal N".
std::string signalName(int signal);

//! Peak resident memory of this process from /proc/self/status (VmHWM), MB; 0 when unavailable.
double peakRssMb();

//! CPU time (user + system) used by this process so far, seconds.
double processCpuSeconds();

/*!
  Write the statistics of a run as a flat JSON object (numbers, strings, booleans, null for what is unknown).
  \param params : the settings the run used (tracking mode, deterministic).
  \exception vpHSlamException::fileUnreadable when the file cannot be written.
*/
void writeStats(const std::string &path, const vpHSlam::Statistics &s, const Arguments &args,
                const vpHSlamParameters &params, const RunOutcome &outcome);
} // namespace hslam_dataset

#endif
