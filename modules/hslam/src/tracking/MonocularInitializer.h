/*
 * H-SLAM for ViSP.
 */
/*!
  \file MonocularInitializer.h
  \brief Monocular initialisation from the tracking thread's side: two-view attempts on the incoming frames
  (TwoViewInitializer: ORB matches, essential / homography), and once the first map exists, the frames seen meanwhile
  tracked backwards against it, so the trajectory covers the sequence from its first frame.

  In tracking/, not mapping/: it runs in the tracking thread on the frames as they come, keeps their raw images, and
  what it hands back are frame poses (the two-view result, then the backfilled poses); making the first map from the
  two-view result is the mapper's (LocalMapper::initialize), called by the conductor.

  Owns: the TwoViewInitializer and its first frame, the frames seen while initialising (raw, the newest
  Initializer::maxFramesToInitialize of them), the CoarseTracker the backfill aligns with.
  Is given: each frame before the map exists (preprocessed, with its raw input); for the backfill, a function that
  sets the first map's tracking reference (the second keyframe) in a tracker, and one that preprocesses a kept frame.
  Hands back: the two-view result and its first frame; the backfilled frames' poses relative to the second keyframe.

  Threading: the tracking thread.
*/
#ifndef HSLAM_TRACKING_MONOCULAR_INITIALIZER_H
#define HSLAM_TRACKING_MONOCULAR_INITIALIZER_H

#include "map/AffineBrightness.h"
#include "map/Frame.h"
#include "mapping/TwoViewInitializer.h"
#include "math/SE3.h"
#include "tracking/CoarseTracker.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <deque>
#include <functional>
#include <memory>
#include <vector>

namespace hslam
{
class VISP_EXPORT MonocularInitializer
{
public:
  //! A frame seen while initialising, kept as its raw input (cheap) to be tracked once the map exists.
  struct PendingFrame {
    vpImage<unsigned char> I;
    double timestamp = 0.;
    double exposure = -1.;
    int id = -1;
  };
  //! A frame given a pose by the backfill.
  struct BackfilledFrame {
    int id = -1;
    double timestamp = 0.;
    SE3d refMc; //!< relative to the second keyframe
  };
  //! Sets the tracking reference of the first map (its second keyframe) in a tracker, with its brightness.
  using ReferenceSetter = std::function<bool(CoarseTracker &tracker, AffineBrightness &affine)>;
  //! Preprocesses a kept frame.
  using Preprocess = std::function<FramePtr(const PendingFrame &pending)>;

  MonocularInitializer(const vpHSlamParameters &params, const PinholeIntrinsics &K, bool photometricCalibration);
  ~MonocularInitializer();

  /*!
    One two-view attempt with \e frame (raw input \e I, \e exposure). True when it initialised against a first frame
    still held: then firstFrame() and result() are the pair to make the map from.
  */
  bool addFrame(const FramePtr &frame, const vpImage<unsigned char> &I, double exposure);
  const FramePtr &firstFrame() const { return m_firstFrame; }
  const TwoViewInitialization &result() const { return m_initializer.result(); }
  //! The map could not be made from the pair: \e frame is the first frame of the next attempts.
  void restartFrom(const FramePtr &frame);
  /*!
    After the map was made from frames \e firstFrameId and \e secondFrameId (relative pose \e c2Mc1): the kept frames
    tracked backwards against the second keyframe, in the order they were tracked (newest first), until the first
    that fails. The kept frames are then forgotten.
  */
  std::vector<BackfilledFrame> backfill(const SE3d &c2Mc1, int firstFrameId, int secondFrameId,
                                        const ReferenceSetter &setReference, const Preprocess &preprocess);
  //! Forget the attempt and the kept frames (a new segment, a reset, or initialised).
  void reset();

private:
  vpHSlamParameters m_params;
  bool m_photometricCalibration;
  TwoViewInitializer m_initializer;
  FramePtr m_firstFrame; //!< the initializer's current first frame
  //! Frames after m_firstFrame, oldest first. A deque: the oldest leaves by pop_front, never by moving the others
  //! (a vector's erase assigns vpImages, and ViSP 3.5's vpImage assignment leaked their buffers: LeakSanitizer).
  std::deque<PendingFrame> m_pending;
  std::unique_ptr<CoarseTracker> m_backfillTracker;
};
} // namespace hslam

#endif
