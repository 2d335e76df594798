/*
 * H-SLAM for ViSP.
 */
/*!
  \file HybridTracker.h
  \brief The indirect step of hybrid pose tracking (paper section 3.2, step 1) and the keypoints of a new frame.

  extract(): FAST corners of the new frame (spread by CornerDetector) with oriented ORB descriptors at level 0, the
  same computation as the map points' (descriptor sharing), so that descriptors compare across frames.
  indirectStep(): the reference's points with descriptors are projected into the new frame with the predicted
  (constant-velocity) pose and matched by ORB inside a search radius (Hamming threshold, ratio test, rotation
  consistency: OrbMatcher); when fewer than Tracking::minMatchesBeforeWidening match, the search is repeated with
  twice the radius, and when that still fails, the points are matched to every keypoint by descriptor alone and a
  PnP RANSAC gives the start of a new guided search (ORB-SLAM2 tracks against the reference keyframe by BoW in that
  case; here exhaustive matching, a few hundred corners against a thousand keypoints, well under a millisecond). A
  robust pose-only optimisation of the reprojection error (PoseOnlyOptimizer) gives the pose and the geometric inliers,
  which form the GeometricTerm of the joint optimisation, with s_g^2 the mean squared reprojection error of those
  inliers.

  Threading: not thread-safe; one per tracking thread.
*/
#ifndef HSLAM_TRACKING_HYBRID_TRACKER_H
#define HSLAM_TRACKING_HYBRID_TRACKER_H

#include "features/CornerDetector.h"
#include "features/OrbMatcher.h"
#include "features/PointDescriptors.h"
#include "tracking/CoarseTracker.h"
#include "tracking/PoseOnlyOptimizer.h"
#include "tracking/Relocalizer.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <vector>

namespace hslam
{
//! Outcome of HybridTracker::indirectStep().
struct IndirectStepResult {
  bool usable = false;    //!< at least Tracking::minGeometricInliers inliers
  int matches = 0;        //!< ORB matches
  int inliers = 0;        //!< after the pose-only optimisation
  bool recovered = false; //!< the prediction was abandoned for a pose found without one (large motion)
  SE3d newMref;           //!< pose-only estimate (the prediction when not usable)
  GeometricTerm term;     //!< the inlier matches, for the joint optimisation
};

class VISP_EXPORT HybridTracker
{
public:
  HybridTracker(const vpHSlamParameters &params, const PinholeIntrinsics &K0, int width, int height);

  //! Keypoints and descriptors of a new frame (rectified 8-bit image); replaces the previous ones.
  void extract(const vpImage<unsigned char> &raw);
  const std::vector<FrameKeypoint> &keypoints() const { return m_keypoints; }
  //! The same keypoints as relocalisation takes them (pixels and descriptors, no direct index yet).
  RelocalizationFrame relocalizationFrame() const;

  /*!
    Match \e features (reference frame) into the frame given to extract(), starting from \e predictedMref, and
    estimate the pose from the matches. Returns out.usable.
  */
  bool indirectStep(const std::vector<ReferenceFeature> &features, const SE3d &predictedMref, IndirectStepResult &out);

private:
  //! Paper eq. 3 weights of the inliers of \e pose (see GeometricTerm::weights), with the count and variance they give.
  void weighByDepthVariance(const std::vector<ReprojectionObservation> &observations,
                            const std::vector<double> &idepthVars, const PoseOnlyResult &pose,
                            GeometricTerm &term) const;
  //! Fill m_projected / m_projectedFeature with the features landing in the image at \e newMref.
  void project(const std::vector<ReferenceFeature> &features, const SE3d &newMref);
  /*!
    Too few matches around the prediction: match the features to every keypoint by descriptor alone, PnP RANSAC,
    pose-only refinement. Returns false when that does not give Tracking::minMatchesBeforeWidening inliers.
  */
  bool recoverFromLargeMotion(const std::vector<ReferenceFeature> &features, SE3d &newMref) const;

  vpHSlamParameters::Tracking m_params;
  double m_cornerMinDistance;
  PinholeIntrinsics m_K0;
  int m_width, m_height;
  PointDescriptors m_descriptors;
  std::vector<FrameKeypoint> m_keypoints;
  // scratch
  std::vector<cv::Point2f> m_pixels;
  CornerThresholdHint m_cornerHint; //!< where the next frame's corner detection starts (speed only)
  std::vector<OrbDescriptor> m_desc;
  std::vector<bool> m_valid;
  std::vector<float> m_angles;
  std::vector<ProjectedPoint> m_projected;
  std::vector<int> m_projectedFeature;
};
} // namespace hslam

#endif
