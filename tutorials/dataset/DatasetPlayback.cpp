#include "dataset/DatasetPlayback.h"

#include <visp3/hslam/vpHSlamException.h>

#include <algorithm>
#include <utility>

namespace hslam_dataset
{
namespace
{
//! Median of the intervals between consecutive stamps of \e kept (at least two frames).
template <typename Kept> double medianInterval(const std::deque<Kept> &kept)
{
  std::vector<double> intervals;
  intervals.reserve(kept.size() - 1);
  for (std::size_t i = 1; i < kept.size(); ++i) {
    intervals.push_back(kept[i].played.frame.timestamp - kept[i - 1].played.frame.timestamp);
  }
  const std::size_t middle = intervals.size() / 2;
  std::nth_element(intervals.begin(), intervals.begin() + static_cast<std::ptrdiff_t>(middle), intervals.end());
  double median = intervals[middle];
  if (intervals.size() % 2 == 0) {
    // Even count: the mean of the two middle values (the lower one is the largest of the first half).
    median =
        0.5 * (median + *std::max_element(intervals.begin(), intervals.begin() + static_cast<std::ptrdiff_t>(middle)));
  }
  return median;
}
} // namespace

FramePlayback::FramePlayback(vpHSlamImageSource &source, const Arguments &args, DropReport onDropped)
    : m_source(source), m_args(args), m_onDropped(std::move(onDropped))
{
  if (m_args.thereAndBack && m_source.getFormat() == vpHSlamImageSource::formatV4l2) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "--there-and-back needs a recorded sequence, not a live camera: a camera has no last "
                           "frame to turn back at");
  }
}

bool FramePlayback::next(vpImage<unsigned char> &I, PlayedFrame &played)
{
  if (!m_sourceEnded && readForward(I, played)) {
    record(played);
    return true;
  }
  if (playBackward(I, played)) {
    record(played);
    return true;
  }
  return false;
}

double FramePlayback::getPlayedSeconds() const
{
  const double forward =
      m_framesRead > 1 ? (m_lastReadStamp - m_firstReadStamp) * m_framesRead / (m_framesRead - 1) : 0.;
  return forward + m_backwardFrames * m_backwardInterval;
}

bool FramePlayback::acquireReadable(vpImage<unsigned char> &I, vpHSlamImageSource::Frame &frame)
{
  while (true) {
    try {
      const bool got = m_source.acquire(I, frame);
      m_consecutiveUnreadable = 0;
      return got;
    } catch (const vpHSlamException &e) {
      // The source consumed the frame it could not read: the next acquire() reads the one after.
      if (!m_args.skipUnreadable || e.getCode() != vpHSlamException::fileUnreadable ||
          ++m_consecutiveUnreadable >= kMaxConsecutiveUnreadable) {
        throw;
      }
      ++m_droppedFrames;
      if (m_onDropped) {
        m_onDropped(e.getStringMessage());
      }
    }
  }
}

bool FramePlayback::readForward(vpImage<unsigned char> &I, PlayedFrame &played)
{
  vpHSlamImageSource::Frame frame;
  while (acquireReadable(I, frame)) {
    if (m_framesRead == 0) {
      m_firstReadStamp = frame.timestamp;
    }
    m_lastReadStamp = frame.timestamp;
    ++m_framesRead;
    // --stride and --blackout go by the source's numbering (after --start-frame; an unreadable frame dropped by
    // --skip-unreadable keeps its number), so a run with dropped frames still tracks the same frames.
    if (!m_args.feeds(frame.index)) {
      continue;
    }
    played = PlayedFrame();
    played.frame = frame;
    played.sourceTimestamp = frame.timestamp;
    played.blackedOut = m_args.blacksOut(frame.index);
    if (played.blackedOut) {
      I = 0; // a covered lens: same size, same timestamp and exposure
      ++m_blackedOutFrames;
    }
    if (m_args.thereAndBack) {
      Kept kept;
      kept.played = played;
      kept.width = I.getWidth();
      kept.height = I.getHeight();
      if (!played.blackedOut) {
        kept.image = I;
      }
      m_kept.push_back(std::move(kept));
    }
    return true;
  }
  m_sourceEnded = true;
  return false;
}

void FramePlayback::startBackward()
{
  // The last frame there is the turning point: tracked once. The way back starts with the one before it.
  m_backwardOrigin = m_kept.back().played.frame.timestamp;
  m_backwardInterval = medianInterval(m_kept);
  m_kept.pop_back();
}

bool FramePlayback::playBackward(vpImage<unsigned char> &I, PlayedFrame &played)
{
  if (!m_args.thereAndBack) {
    return false;
  }
  if (!m_backwardStarted) {
    m_backwardStarted = true;
    if (m_kept.size() < 2) {
      m_kept.clear(); // one frame there (or none): nothing to come back over
      return false;
    }
    startBackward();
  }
  if (m_kept.empty()) {
    return false;
  }
  Kept &kept = m_kept.back();
  played = kept.played;
  played.backward = true;
  ++m_backwardFrames;
  played.frame.timestamp = m_backwardOrigin + m_backwardFrames * m_backwardInterval;
  if (played.blackedOut) {
    I.resize(kept.height, kept.width, 0);
    ++m_blackedOutFrames;
  } else {
    I = std::move(kept.image);
  }
  m_kept.pop_back(); // memory shrinks on the way back
  return true;
}

void FramePlayback::record(const PlayedFrame &played)
{
  FedStamp stamp;
  stamp.timestamp = played.frame.timestamp;
  stamp.sourceTimestamp = played.sourceTimestamp;
  stamp.index = played.frame.index;
  stamp.backward = played.backward;
  m_fed.push_back(stamp);
}
} // namespace hslam_dataset
