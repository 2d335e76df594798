// The frames tutorial-hslam-dataset gives to tracking, in their order: the source read once, the source decorators
// applied (--skip-unreadable, --stride, --blackout) and, with --there-and-back, the way back played from memory.
#ifndef HSLAM_TUTORIAL_DATASET_PLAYBACK_H
#define HSLAM_TUTORIAL_DATASET_PLAYBACK_H

#include "dataset/DatasetArguments.h"

#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamImageSource.h>

#include <deque>
#include <functional>
#include <string>
#include <vector>

namespace hslam_dataset
{
//! A frame given to tracking and where it comes from.
struct PlayedFrame {
  //! As the source delivered it (index: source numbering after --start-frame), except the timestamp: on the way back
  //! it is the re-timed one, the stamp the frame is tracked under.
  vpHSlamImageSource::Frame frame;
  double sourceTimestamp = 0.; //!< the source's own timestamp of this image
  bool backward = false;       //!< played on the way back (--there-and-back)
  bool blackedOut = false;     //!< replaced by a black image (--blackout)
};

//! The two timestamps of a frame given to tracking: the one it was tracked under and the source's own.
struct FedStamp {
  double timestamp = 0.;       //!< stamp given to vpHSlam::track(), so the stamp of its pose in the trajectory
  double sourceTimestamp = 0.; //!< stamp of the image in the source (equal to timestamp on the way there)
  unsigned int index = 0;      //!< source index of the image (after --start-frame)
  bool backward = false;       //!< on the way back (--there-and-back)
};

/*!
  Reads a vpHSlamImageSource once and yields the frames to track, in order.

  Way there: the frames the source delivers (after --start-frame, at most --max-frames), an unreadable one skipped
  with --skip-unreadable (it keeps its number), those whose source index is a multiple of --stride given to
  tracking, the ones in --blackout replaced by a black image. Their timestamps are the source's.

  Way back (--there-and-back, when the way there reached the end of the source): the M frames given to tracking on
  the way there are replayed in reverse order from the second-to-last to the first (M - 1 more frames, so 2M - 1 in
  all), from memory: the source classes can neither seek nor re-open at a frame (and a video or a zip would be
  decoded again from its start for every frame), so the grey images given to tracking are kept (a blacked-out frame
  keeps only its size), and each is released once replayed. The k-th frame back (k = 1 .. M - 1) shows way-there
  frame M - 1 - k and is stamped t_last + k dt, with t_last the last way-there stamp and dt the median interval
  between consecutive way-there frames given to tracking (the source's frame interval times --stride; the median
  ignores the longer gap of a dropped frame, and every source format has stamps, not all a frame rate). A frame
  blacked out on the way there is black on the way back (--blackout goes by source index).

  A way there cut short by an error thrown from next() or by the caller stopping has no way back.
*/
class FramePlayback
{
public:
  //! Called with the message of each frame skipped by --skip-unreadable.
  using DropReport = std::function<void(const std::string &)>;

  /*!
    \param source : read by next(); must outlive this object.
    \param args : --stride, --blackout, --skip-unreadable, --there-and-back (copied).
    \param onDropped : told about each unreadable frame skipped (may be empty).
    \exception vpHSlamException::invalidArgument with --there-and-back on a live camera (a sequence without an end).
  */
  FramePlayback(vpHSlamImageSource &source, const Arguments &args, DropReport onDropped = DropReport());

  /*!
    Next frame to track. \return false when there is none left.
    \exception vpHSlamException from the source (an unreadable frame when it is not skipped, a corrupt list, ...).
  */
  bool next(vpImage<unsigned char> &I, PlayedFrame &played);

  //! Source stamp of the first frame read (0 before), the origin of real-time pacing.
  double getFirstStamp() const { return m_firstReadStamp; }
  //! Frames read from the source (given to tracking or skipped by --stride; not the way back, not the dropped).
  unsigned int getFramesRead() const { return m_framesRead; }
  //! Unreadable frames skipped (--skip-unreadable).
  unsigned int getDroppedFrames() const { return m_droppedFrames; }
  //! Frames given to tracking as a black image, both ways.
  unsigned int getBlackedOutFrames() const { return m_blackedOutFrames; }
  //! Frames given to tracking on the way back.
  unsigned int getBackwardFrames() const { return m_backwardFrames; }
  //! Interval between the stamps of the way back, seconds (0 until the way back starts).
  double getBackwardInterval() const { return m_backwardInterval; }
  //! Seconds of sequence played: the frames read (their stamps' span plus one frame) and the way back.
  double getPlayedSeconds() const;
  //! Stamps of every frame given to tracking so far, in order.
  const std::vector<FedStamp> &getFedStamps() const { return m_fed; }

private:
  //! A way-there frame given to tracking, kept for the way back.
  struct Kept {
    PlayedFrame played;
    vpImage<unsigned char> image; //!< empty for a blacked-out frame (black again on the way back)
    unsigned int width = 0, height = 0;
  };

  bool readForward(vpImage<unsigned char> &I, PlayedFrame &played);
  bool acquireReadable(vpImage<unsigned char> &I, vpHSlamImageSource::Frame &frame);
  bool playBackward(vpImage<unsigned char> &I, PlayedFrame &played);
  void startBackward();
  void record(const PlayedFrame &played);

  vpHSlamImageSource &m_source;
  const Arguments m_args;
  DropReport m_onDropped;
  bool m_sourceEnded = false;
  bool m_backwardStarted = false;
  unsigned int m_consecutiveUnreadable = 0;
  unsigned int m_framesRead = 0;
  unsigned int m_droppedFrames = 0;
  unsigned int m_blackedOutFrames = 0;
  unsigned int m_backwardFrames = 0;
  double m_firstReadStamp = 0.;
  double m_lastReadStamp = 0.;
  double m_backwardInterval = 0.;
  double m_backwardOrigin = 0.; //!< t_last: the stamp the way back continues from
  //! Way-there frames not replayed yet (--there-and-back). A deque: growing it never copies the images (a vector
  //! would, vpImage's move constructor not being noexcept: twice their memory at each reallocation).
  std::deque<Kept> m_kept;
  std::vector<FedStamp> m_fed;
};
} // namespace hslam_dataset

#endif
