/*
 * H-SLAM for ViSP.
 */
/*!
  \file TrajectoryRecorder.h
  \brief The pose of every frame, stored relative to its reference keyframe (DSO's FrameShell bookkeeping).

  Each frame with a pose is recorded as (reference keyframe id, refMc = camera-to-reference transform). Keyframe
  poses wMc are kept here too and updated by the mapper after every window optimisation, so a frame's current
  world pose is wMref * refMc: when the window moves a keyframe, every frame tracked against it moves with it.
  A keyframe is its own reference (identity).

  Keyframe ids index a vector (ids are 0, 1, 2, ... over the whole run, all segments included). Segments are map
  segments: a new one starts after a tracking loss (see vpHSlam).

  Threading: one mutex guards everything; every method is thread-safe (tracking adds frames, mapping updates
  keyframe poses, viewers read snapshots). Held only for copies.
*/
#ifndef HSLAM_SYSTEM_TRAJECTORY_RECORDER_H
#define HSLAM_SYSTEM_TRAJECTORY_RECORDER_H

#include "math/SE3.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include <mutex>
#include <vector>

namespace hslam
{
class VISP_EXPORT TrajectoryRecorder
{
public:
  //! A keyframe's record.
  struct KeyframeRecord {
    int id = -1;
    int frameIndex = -1;
    double timestamp = 0.;
    SE3d wMc;
    unsigned int segment = 0;
    bool inWindow = true;
    unsigned int activePoints = 0;
    bool discarded = false; //!< its segment was discarded (wrong initialisation): not reported
  };
  //! A frame's record.
  struct FrameRecord {
    int frameIndex = -1;
    double timestamp = 0.;
    int referenceKeyframe = -1; //!< keyframe id
    SE3d refMc;                 //!< camera -> reference keyframe camera
    unsigned int segment = 0;
  };

  /*!
    Record a new keyframe with id \e keyframeId (must be the next id: first id + size of the keyframe list).
    \exception vpHSlamException::invalidArgument when ids are not consecutive.
  */
  void addKeyframe(int keyframeId, int frameIndex, double timestamp, const SE3d &wMc, unsigned int segment);
  //! New pose (and window membership) of a keyframe; unknown ids are ignored.
  void updateKeyframe(int keyframeId, const SE3d &wMc);
  /*!
    Id of the first keyframe to be recorded (0 unless a loaded map took the lower ids); only before any keyframe is
    recorded. clear() sets it back to 0.
  */
  void setFirstKeyframeId(int id);
  void setKeyframeInWindow(int keyframeId, bool inWindow, unsigned int activePoints);
  /*!
    Loop correction of keyframes whose map was scaled: each keyframe id gets its new pose, and the frames tracked
    against it have their translation to it divided by its scale factor (their map shrank or grew with it).
  */
  void correctKeyframes(const std::vector<int> &ids, const std::vector<SE3d> &wMc, const std::vector<double> &scale);
  /*!
    Record a frame's pose relative to a recorded keyframe. Frames are kept in the order they are added; adding a
    frame index already recorded replaces its record (a frame that becomes a keyframe is re-anchored to itself).
  */
  void addFrame(int frameIndex, double timestamp, int referenceKeyframe, const SE3d &refMc, unsigned int segment);

  //! Current world pose of keyframe \e id. \exception vpHSlamException::invalidArgument for an unknown id.
  SE3d keyframePose(int keyframeId) const;
  //! Pose of a keyframe that is recorded and not discarded; false otherwise (no exception).
  bool keptKeyframePose(int keyframeId, SE3d &wMc) const;
  //! Current world pose wMc of the recorded frame with the highest index; false when none.
  bool lastFramePose(SE3d &wMc) const;
  //! Current world pose wMc of a recorded frame index; false when not recorded.
  bool framePose(int frameIndex, SE3d &wMc) const;

  /*!
    Forget the frames of a segment and hide its keyframes (ids stay reserved).
    \return the number of frame records removed.
  */
  size_t discardSegment(unsigned int segment);

  size_t frameCount() const;
  //! Keyframes recorded and not discarded.
  size_t keyframeCount() const;
  //! Every keyframe record, discarded ones included (in id order).
  std::vector<KeyframeRecord> keyframes() const;

  //! Every frame (\e segment < 0) or one segment's frames, as camera-to-world poses, in frame index order; with
  //! \e segments, each pose's segment (same order, read under the same lock).
  vpHSlamTrajectory trajectory(int segment = -1, std::vector<unsigned int> *segments = nullptr) const;
  //! The same for the keyframes (id order, discarded ones left out).
  vpHSlamTrajectory keyframeTrajectory(int segment = -1, std::vector<unsigned int> *segments = nullptr) const;
  std::vector<unsigned int> frameSegments() const;

  void clear();

private:
  SE3d worldPoseLocked(const FrameRecord &f) const;
  //! Record of keyframe \e id, null when not recorded.
  KeyframeRecord *findLocked(int id);
  const KeyframeRecord *findLocked(int id) const;

  mutable std::mutex m_mutex;
  std::vector<KeyframeRecord> m_keyframes; //!< keyframe id m_firstId + i at index i
  int m_firstId = 0;
  std::vector<FrameRecord> m_frames;
  std::vector<int> m_frameSlot; //!< frame index -> position in m_frames, -1 when absent
};
} // namespace hslam

#endif
