/*
 * H-SLAM for ViSP.
 */
/*!
  \file KeyframeWindow.h
  \brief The sliding window of keyframes: immature points traced, activated, optimised and marginalised (DSO
  FullSystem::makeKeyFrame's steps; H-SLAM paper sec. 3.2).
*/
#ifndef HSLAM_MAPPING_KEYFRAME_WINDOW_H
#define HSLAM_MAPPING_KEYFRAME_WINDOW_H

#include "features/ImagePyramid.h"
#include "features/SharedPointSelector.h"
#include "map/Frame.h"
#include "map/GlobalMap.h"
#include "map/Keyframe.h"
#include "mapping/ImmaturePointTracer.h"
#include "mapping/PointActivation.h"
#include "mapping/WindowOptimizer.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <map>
#include <vector>

namespace hslam
{
struct TwoViewInitialization;

/*!
  The window of the newest keyframes (mapper.windowSize) with their points.

  What it owns: the window's keyframes (oldest first) with their immature and active points, the epipolar tracer,
  point activation (distance map), the pixel selector with its descriptor sharing, and the photometric window
  optimiser with its marginalisation prior; the checks of a segment's first keyframes (DSO's RMSE test on keyframes
  2 to 4).

  What it is given: frames with a tracked pose (cMw), to trace (trace()) or to become the newest keyframe
  (insertKeyframe()); the stored keyframes (GlobalMap) whose poses anchored points refer to (optimize()).

  What it hands back: the keyframes to marginalise after an optimisation and, for each, its pose-pose information
  (leavingPairs()) and the keyframe itself with its final points (marginalize(), then erase() once the caller stored
  it); point refinement for points brought in from outside (refineNewPoint()); counts, memory, states.

  A keyframe's steps are the caller's to order (LocalMapper::makeKeyframe): trace, insert (activation), optimise,
  drop points out of view, select new immature points, marginalise. Threading: not thread-safe; the mapping
  thread (or the caller in deterministic mode) owns it. Frames given to it are then owned by it; their poses and
  brightness are written here.
*/
class VISP_EXPORT KeyframeWindow
{
public:
  /*!
    \param withDescriptors : every selected point gets an ORB descriptor (descriptor sharing: hybrid or indirect
    tracking, or a global map).
  */
  KeyframeWindow(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height,
                 bool photometricCalibration, bool withDescriptors);

  /*!
    The first two keyframes from a two-view initialisation (see LocalMapper::initialize()): the first gets points
    interpolated from the triangulated matches, traced into the second and refined photometrically. False (the
    window unchanged but for the optimiser) when too few points could be made: the caller starts a fresh window.
    The second keyframe still has to go through the keyframe steps from "optimise" on.
  */
  bool initialize(const FramePtr &first, int firstKeyframeId, const FramePtr &second, int secondKeyframeId,
                  const TwoViewInitialization &init, const SE3d &wMfirst);
  //! After the second keyframe's steps: the first keyframe's corners, described and never activated.
  void addFirstKeyframeCorners();
  //! Trace the immature points of the window in \e frame (pose already set).
  void trace(const Frame &frame);
  //! \e frame becomes the newest keyframe; the window's immature points are activated against it.
  KeyframePtr insertKeyframe(const FramePtr &frame, int keyframeId);
  //! DSO flagFramesForMarginalization: the keyframes to leave after this keyframe's optimisation.
  std::vector<int> keyframesToMarginalize() const { return m_optimizer.keyframesToMarginalize(); }
  /*!
    The window optimisation after keyframe \e kf was inserted: anchors re-read from \e stored, optimisation, anchor
    outliers dropped, DSO's initialisation check; the pose-pose information of \e leaving is kept for leavingPairs()
    when \e keepPairs.
  */
  void optimize(const Keyframe &kf, const GlobalMap &stored, const std::vector<int> &leaving, bool keepPairs);
  //! DSO flagPointsForRemoval: active points that no longer project into \e newest leave the optimisation.
  void dropPointsOutOfView(const Keyframe &newest);
  //! Select a keyframe's new immature points: corners and gradient pixels, or its corners only.
  void makeNewImmaturePoints(Keyframe &kf, bool cornersOnly = false);
  //! The keyframe of id \e id in the window, null when none.
  KeyframePtr find(int id) const;
  //! Pose-pose links of keyframe \e id with the window: those kept by optimize(), else from the current state.
  std::vector<PairInformation> leavingPairs(int id);
  //! Pose-pose links of keyframe \e id with the window at the current state.
  std::vector<PairInformation> pairInformation(int id) { return m_optimizer.pairInformation(id); }
  //! Marginalise keyframe \e id out of the optimisation; its converged descriptor-only points become map points. It
  //! stays in keyframes() until erase(): the caller stores it first.
  void marginalize(int id);
  void erase(int id);
  //! Photometric refinement of a point brought into keyframe \e hostId (PointActivation's Gauss-Newton).
  PointActivationResult refineNewPoint(int hostId, const ImmaturePoint &pt, double idepth, double priorIdepth,
                                       double priorWeight) const;

  //! A lost camera was relocalised into this segment's map: the initialisation check stops (see
  //! LocalMapper::noteRelocalization()).
  void noteRelocalization() { m_relocalizedInSegment = true; }
  bool initializationFailed() const { return m_initializationFailed; }

  const std::vector<KeyframePtr> &keyframes() const { return m_window; }
  bool empty() const { return m_window.empty(); }
  size_t size() const { return m_window.size(); }
  bool withDescriptors() const { return m_selector.withDescriptors(); }
  int activePointCount() const;
  int immaturePointCount() const;
  //! Bytes held by the window's keyframes (pyramids, images, points).
  double memoryBytes() const;
  /*!
    Points of the window in world coordinates (appended): active ones with status 0, the others (marginalised, not
    outliers) with status 1; only the active ones when \e activeOnly (\e status may then be null).
  */
  void pointsWorld(std::vector<Eigen::Vector3d> &points, std::vector<int> *status, bool activeOnly) const;

private:
  void activatePoints(const Keyframe &newest);
  //! Median inverse depth of the window's active points (each in its host), 0 when there is none.
  double medianActiveIdepth() const;
  /*!
    Whether the two-view geometry of the segment's keyframe pairs (all but the first two together) confirms the
    window's motion: at least one pair measured, and every measured pair agrees (InitializationCheck.h).
  */
  bool segmentMotionConfirmed() const;
  /*!
    Turning in place: candidate \e c of \e host, refused by the Hessian test, is kept on a weak prior at
    \e medianIdepth (clamped into its interval) when the translation from \e host to \e newest moves that depth by
    less than mapper.rotationFlowPx and its residuals agree. Then \e r, \e priorIdepth and \e priorWeight (1 /
    variance) are set and true returned.
  */
  bool activateOnDepthPrior(const Keyframe &newest, const Keyframe &host, const ActivationCandidate &c,
                            double medianIdepth, PointActivationResult &r, double &priorIdepth,
                            double &priorWeight) const;
  //! Initial points of the first keyframe: selected pixels traced into \e second around the interpolated prior.
  std::vector<ImmaturePoint> traceInitialPoints(const Frame &first, const Frame &second,
                                                const TwoViewInitialization &init);
  //! Re-read the stored poses the window's re-used points are anchored to (a loop correction moves them); an
  //! anchor whose keyframe left the global map is dropped.
  void refreshAnchors(const GlobalMap &stored);
  //! After an optimisation: anchors whose point lands more than globalMap.anchorMaxErrorPx from its stored pixel are
  //! dropped (a wrong match, or a stored point the window disagrees with); returns how many.
  int dropAnchorOutliers();
  //! Descriptor sharing: ORB descriptors for points [begin, end) of \e points, hosted by \e frame.
  void describe(const Frame &frame, std::vector<ImmaturePoint> &points, size_t begin);

  vpHSlamParameters m_params;
  PinholeIntrinsics m_K0;
  int m_width, m_height;
  ImmaturePointTracer m_tracer;
  PointActivation m_activation;
  SharedPointSelector m_selector;
  WindowOptimizer m_optimizer;
  std::vector<KeyframePtr> m_window;         //!< oldest first
  std::vector<SelectedPixel> m_selected;     //!< scratch of the pixel selection
  std::vector<bool> m_selectedCorner;        //!< per selected pixel: a FAST corner
  std::vector<cv::Point2f> m_describePixels; //!< scratch of describe()
  std::vector<OrbDescriptor> m_describeOut;
  std::vector<bool> m_describeValid;
  std::vector<float> m_describeAngles;
  int m_keyframesInSegment = 0;
  bool m_relocalizedInSegment = false; //!< see noteRelocalization()
  bool m_initializationFailed = false;
  double m_initNoiseSigma = 0.; //!< image noise of the segment's first keyframe (estimateNoiseSigma), intensity units
  std::map<int, std::vector<PairInformation>> m_pendingPairs; //!< pose-pose links of the keyframes being marginalised
};
} // namespace hslam

#endif
