/*
 * H-SLAM for ViSP.
 */
/*!
  \file MetricFrame.h
  \brief The similarity that makes the map metric (and, with a tag id, expressed in the tag's frame), fitted to a
  described AprilTag's sightings in keyframes.

  What it is for: monocular SLAM poses are up to scale, in the frame of the first keyframe. A tag of known size seen
  from a keyframe gives that keyframe's camera pose in the tag's frame in metres (features/TagDetector.h). With the
  keyframes' SLAM poses wMc_i, every sighting i relates the two frames:
    camera centre   q_i = tMc_i.t = s R p_i + t      (p_i = wMc_i.t)
    orientation     tRc_i = R wRc_i
  for the similarity mSw = (s, R, t) from the SLAM world to the metric one, fitted robustly by fitMetricFrame()
  (map/MetricFit.h) to every sighting of the segment, with the tag's depth in the map (the window's points inside
  the tag against the tag plane's metric depth) as the scale's main evidence. A camera that only rotates in front of
  the tag becomes metric through that depth alone.
  Without a tag id, the output keeps SLAM's world frame and only takes the scale: mSw = (s, I, 0).

  Only sightings of the current map segment are fitted (a new segment after a loss has its own scale): startSegment()
  forgets the fit, and the frame is not metric in a segment where the tag was never seen; outputs of other segments
  are left in their own units (appliesTo()). Each refit reads the keyframes' current poses, so window optimisation
  and loop corrections flow into the frame; a loop correction that rescales keyframes rescales their sightings'
  depth measurements too (rescaleKeyframes()).

  Threading: observeKeyframe(), addSightings(), refit() and clear() from the back end, setTag() from the caller's
  thread (the detector has its own mutex); current() and the output conversions from any thread (a mutex guards the
  result). Given: keyframe images (or sightings) and keyframe poses. Hands back: the fit, and outputs converted by it.
*/
#ifndef HSLAM_MAP_METRIC_FRAME_H
#define HSLAM_MAP_METRIC_FRAME_H

#include "features/TagDetector.h"
#include "map/MapFile.h"
#include "map/MetricFit.h"
#include "math/SE3.h"
#include "math/Sim3.h"

#include <visp3/core/vpCameraParameters.h>
#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamTag.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include <functional>
#include <memory>
#include <mutex>
#include <vector>

namespace hslam
{
/*!
  The output frame of a fit: wMc (SLAM world, map units) as the camera pose in the output world, metres when the fit
  is metric; identity when it is not (poses stay in the SLAM frame until the fit is trusted).
*/
VISP_EXPORT SE3d outputPose(const MetricFit &fit, const SE3d &wMc);
//! Whether \e fit converts the outputs of map segment \e segment (metric, and fitted in it or loaded for all).
VISP_EXPORT bool appliesTo(const MetricFit &fit, unsigned int segment);
//! The same for a point.
VISP_EXPORT Eigen::Vector3d outputPoint(const MetricFit &fit, const Eigen::Vector3d &pw);

//! A fit as a map file keeps it (present only when metric).
VISP_EXPORT MapMetricFrame toMapMetricFrame(const MetricFit &fit);
//! A map file's metric frame as a fit (metric when present).
VISP_EXPORT MetricFit fromMapMetricFrame(const MapMetricFrame &frame);

class VISP_EXPORT MetricFrame
{
public:
  //! Keyframe poses by id: false for a keyframe that has none (unknown, or its segment discarded).
  using PoseLookup = std::function<bool(int, SE3d &)>;
  //! The window's active points, SLAM world (their depths are what measures the tag's depth in the map).
  using PointLookup = std::function<void(std::vector<Eigen::Vector3d> &)>;
  //! Fewest map points inside a sighting's tag that measure its depth in the map.
  static constexpr int kMinDepthPoints = 5;

  //! No tag: nothing is fitted, current() is never metric.
  MetricFrame() = default;
  MetricFrame(const vpHSlamTag &tag, const vpHSlamParameters::TagFrame &options);
  /*!
    Describe the tag (or none) and forget every sighting; \e K: the rectified pinhole camera of the keyframe images
    observeKeyframe() will get (the detector is made for it).
  */
  void setTag(const vpHSlamTag &tag, const vpHSlamParameters::TagFrame &options, const vpCameraParameters &K);

  /*!
    A new keyframe: the tag is searched for in \e image (rectified, photometrically raw), its sightings stored, and the
    fit made again with the keyframes' current poses. Nothing without a tag.
  */
  void observeKeyframe(int keyframeId, unsigned int segment, const vpImage<unsigned char> &image,
                       const PoseLookup &keyframePose, const PointLookup &windowPoints = nullptr);
  //! Mean tag detection time per keyframe so far, milliseconds.
  double detectionMsMean() const;
  /*!
    \e trajectory (SLAM frame) in the output frame of the current fit: the poses whose segment (\e segments, same
    order) the fit applies to; the others as they are.
  */
  vpHSlamTrajectory toOutput(const vpHSlamTrajectory &trajectory, const std::vector<unsigned int> &segments) const;
  //! A new map segment starts (after a loss): the fit of the previous one no longer applies.
  void startSegment(unsigned int segment);
  /*!
    A loop correction divided the map around keyframes \e ids by \e scales (LocalMapper::KeyframeState::scale: new
    distances = old / scale): their sightings' depth measurements (metres per map unit) are multiplied by it.
  */
  void rescaleKeyframes(const std::vector<int> &ids, const std::vector<double> &scales);

  //! Sightings of keyframe \e keyframeId (segment \e segment), as the detector handed them on.
  void addSightings(int keyframeId, unsigned int segment, const std::vector<TagSighting> &sightings);
  /*!
    Fit again with the keyframes' current poses: \e keyframePose(id, wMc) returns false for a keyframe that no longer
    has one (discarded), whose sightings are then left out. With \e windowPoints, each sighting of the fitted
    segment is also given the tag's depth in the map: the window's points that project inside the tag's corners in
    that keyframe, their depth against the tag plane's metric depth there (median of the ratios, at least
    kMinDepthPoints points; the newest measurement is kept, as the points converge).
  */
  void refit(const PoseLookup &keyframePose, const PointLookup &windowPoints = nullptr);
  //! The last fit, or the loaded one (setLoaded()) while there is none of its own (thread-safe copy).
  MetricFit current() const;
  /*!
    The metric frame of a loaded map (localisation-only runs, whose outputs are in the loaded map's coordinates): used
    by current() until this run fits one of its own. Kept by setTag(); forgotten by clear().
  */
  void setLoaded(const MetricFit &fit);
  //! Sightings stored (all segments and ids).
  unsigned int sightingCount() const;

  //! A sighting of the current segment, as loop closure's pose graphs take it (loop/LandmarkSightings.h).
  struct SegmentSighting {
    int keyframeId;
    int tagId;
    SE3d cMt; //!< metres
  };
  //! The current segment's sightings, oldest first.
  std::vector<SegmentSighting> segmentSightings() const;
  /*!
    Keyframe ids between two sightings of a tag from which the second is a revisit: about three windows, so that the
    camera turning away for a moment is not one, and the map between the two visits has drifted (marginalised).
  */
  static constexpr int kRevisitKeyframes = 20;
  /*!
    Whether keyframe \e keyframeId sees a tag again, at the moment a correction by the tag pays: the first keyframe
    that sees it kRevisitKeyframes or more keyframe ids after the sighting before, and the third in a row (three
    sightings of the present, where one detection's error, a degree or so, would otherwise bend the map). The caller
    asks loop closure for the correction (in slam mode). Not in a long view without a gap: tried (a correction at the
    8th keyframe in a row and every 5th after), the servo's 2.3 m approach to a goal 1 m in front of the tag ended 0.34
    degree from it instead of 0.19 (the far sightings' errors bent the map where it had not drifted).
  */
  bool seenAgain(int keyframeId) const;
  //! Forget every sighting and the fit (reset()).
  void clear();
  vpHSlamTag tag() const; //!< the described tag (a copy; thread-safe)

private:
  struct Stored {
    int keyframeId;
    unsigned int segment;
    int tagId;
    SE3d cMt;
    std::array<Eigen::Vector2d, 4> corners;
    double depthScale; //!< 0 until measured
    int depthPoints;
  };
  //! The depth measurement of refit() for one sighting; false with too few points.
  static bool measureDepthScale(const Stored &sighting, const SE3d &wMc, const vpCameraParameters &K,
                                const std::vector<Eigen::Vector3d> &points, double &scale, int &count);
  vpHSlamTag m_tag;
  vpHSlamParameters::TagFrame m_options;
  std::vector<Stored> m_sightings;
  mutable std::mutex m_mutex; //!< guards the tag, the sightings, the fit and the timing
  MetricFit m_fit;
  MetricFit m_loaded;            //!< setLoaded()
  unsigned int m_segment = 0;    //!< the current map segment (startSegment(), observeKeyframe())
  unsigned int m_generation = 0; //!< bumped by setTag() and clear(): a refit begun before drops its result
  std::mutex m_detectorMutex;    //!< held while the detector runs or is replaced
  std::unique_ptr<TagDetector> m_detector;
  vpCameraParameters m_K; //!< of the keyframe images (pinhole)
  double m_detectionMsTotal = 0.;
  unsigned int m_detections = 0;
};
} // namespace hslam

#endif
