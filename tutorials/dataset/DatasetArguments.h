// Command line of tutorial-hslam-dataset: the options, their parsing and checking, the --help text, and the
// settings they select (defaults, then --config, then the command line).
#ifndef HSLAM_TUTORIAL_DATASET_ARGUMENTS_H
#define HSLAM_TUTORIAL_DATASET_ARGUMENTS_H

#include <visp3/hslam/vpHSlamImageSource.h>
#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamTag.h>

#include <ostream>
#include <string>
#include <vector>

namespace hslam_dataset
{
//! With --skip-unreadable, the run still stops when this many frames in a row cannot be read: the input is then
//! broken as a whole (a wrong folder, a dead disk), not a frame here and there.
constexpr unsigned int kMaxConsecutiveUnreadable = 100;

//! --groundtruth-out: largest |frame stamp - ground-truth stamp| of an association, seconds (tutorial-hslam-evaluate's
//! default --max-dt, so the way there is compared with the poses a plain evaluation would pick).
constexpr double kGroundTruthMaxDt = 0.02;

//! Frames A to B (inclusive) of the source, numbered from 0 after --start-frame (vpHSlamImageSource::Frame::index).
struct FrameInterval {
  unsigned int first = 0;
  unsigned int last = 0;
  bool contains(unsigned int index) const { return index >= first && index <= last; }
  //! "A:B", as given on the command line.
  std::string text() const { return std::to_string(first) + ":" + std::to_string(last); }
};

//! Every option of the program, with its default.
struct Arguments {
  std::string input;
  vpHSlamImageSource::Options options;
  std::string mode;                  //!< vo-strict, vo-reuse or slam; empty: as --config (or the default, slam) says
  std::string trackingMode;          //!< direct, indirect, hybrid or adaptive; empty: as --config (or the default) says
  std::vector<std::string> settings; //!< --set SECTION.KEY=VALUE, in order (applied after --config)
  bool deterministic = false;
  double speed = 1.; //!< real-time mode: play the sequence at this multiple of its frame rate (0: no pacing)
  //! Only frames whose source index is a multiple of this are given to tracking (large inter-frame motion).
  unsigned int stride = 1;
  bool blackout = false;        //!< replace the frames of blackoutFrames by a black image (a covered lens)
  FrameInterval blackoutFrames; //!< meaningful when blackout is true
  //! --there-and-back: after the frames selected (--start-frame, --max-frames, --stride), the same frames in reverse
  //! order from the second-to-last, re-timed after the last one (see FramePlayback).
  bool thereAndBack = false;
  std::string groundTruth;    //!< --groundtruth: the ground truth (TUM) --groundtruth-out is made from
  std::string groundTruthOut; //!< --groundtruth-out: ground truth of the frames given to tracking, as tracked
  std::string config;
  std::string trajectory;
  std::string keyframes;
  std::string stats;
  std::string mapPly;            //!< --map-ply: the map as a PLY point cloud
  std::string mapPng;            //!< --map-png: top view of map and trajectory
  std::string saveMap;           //!< --save-map: the map file at the end (vpHSlam::saveMap)
  std::string loadMap;           //!< --load-map: a map file loaded before the first frame (vpHSlam::loadMap)
  bool localizationOnly = false; //!< --localization-only: locate frames in the loaded map, never change it
  vpHSlamTag tag;                //!< --tag FAMILY:SIZE[:ID]: metric output from an AprilTag (not set: none)
  std::string saveConfig;
  std::string logLevel = "warning";
  bool display = true;
  std::string screenshot; //!< PNG of the last view drawn (needs a display)
  bool quiet = false;
  bool skipUnreadable = false; //!< count undecodable frames as dropped and carry on (default: stop with the error)
  bool help = false;

  //! Whether the frame of source index \e index is given to vpHSlam::track() (--stride).
  bool feeds(unsigned int index) const { return index % stride == 0; }
  //! Whether the frame of source index \e index is replaced by a black image (--blackout).
  bool blacksOut(unsigned int index) const { return blackout && blackoutFrames.contains(index); }
  //! --blackout as given ("A:B"), empty when none.
  std::string blackoutText() const { return blackout ? blackoutFrames.text() : std::string(); }
};

//! The --help text.
void printUsage(const char *program, std::ostream &out);

/*!
  Parse and check the command line.
  \exception vpHSlamException::invalidArgument naming the option and the value refused (unknown option, missing or
  malformed value, missing --input).
*/
Arguments parseArguments(int argc, const char *const argv[]);

/*!
  Settings: defaults, then --config, then --set, then the command line (--mode, --tracking-mode, --deterministic);
  validated.
  \exception vpHSlamException when the configuration cannot be read, a name is unknown or a mode is not
  implemented.
*/
vpHSlamParameters makeParameters(const Arguments &args);
} // namespace hslam_dataset

#endif
