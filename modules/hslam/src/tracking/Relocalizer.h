/*
 * H-SLAM for ViSP.
 */
/*!
  \file Relocalizer.h
  \brief Relocalisation of a lost frame against the keyframes place recognition proposes (paper section 3.2,
  failure recovery; ORB-SLAM2's Tracking::Relocalization).

  For each candidate keyframe, best first: ORB matches between the keyframe's map points and the frame's keypoints,
  searched only among features under the same vocabulary node (the direct index: SearchByBoW); when enough match, a
  PnP RANSAC (OpenCV's solvePnPRansac, EPnP hypotheses) gives a pose and its inliers, which the robust pose-only
  optimisation refines and re-classifies. The first candidate that keeps enough inliers wins. The system then
  refines that pose photometrically against the keyframe before tracking resumes in the same map.

  Threading: free function, no state; reads its inputs only.
*/
#ifndef HSLAM_TRACKING_RELOCALIZER_H
#define HSLAM_TRACKING_RELOCALIZER_H

#include "features/BinaryDescriptor.h"
#include "features/BowVector.h"
#include "tracking/PoseOnlyOptimizer.h"

#include <visp3/core/vpConfig.h>

#include <vector>

namespace hslam
{
//! What relocalisation needs of a keyframe: its map points with their descriptors and direct index.
struct RelocalizationKeyframe {
  int id = -1;
  std::vector<Eigen::Vector3d> wX;        //!< map points, world coordinates
  std::vector<OrbDescriptor> descriptors; //!< one per point
  FeatureVector direct;                   //!< direct index of \e descriptors (OrbVocabulary::transform)
};

//! The lost frame: keypoints with descriptors and their direct index.
struct RelocalizationFrame {
  std::vector<Eigen::Vector2d> uv;        //!< keypoint pixels
  std::vector<OrbDescriptor> descriptors; //!< one per keypoint
  FeatureVector direct;                   //!< with the same levelsUp as the keyframes'
  //! Scale factor of the pyramid level each keypoint was detected at (its pixel noise grows with it); empty: 1.
  std::vector<float> scale;
};

//! Settings (defaults: ORB-SLAM2's relocalisation).
struct RelocalizerOptions {
  int maxDistance = 50;       //!< Hamming distance accepted at most in the BoW search (ORB-SLAM2 TH_LOW)
  float ratio = 0.75f;        //!< best below ratio x second best (ORB-SLAM2: 0.75 in relocalisation)
  int minMatches = 15;        //!< BoW matches needed to try PnP with a keyframe, and inliers of a near miss
  int ransacIterations = 300; //!< PnP RANSAC iterations
  bool minimalP3P = false;    //!< AP3P hypotheses from 4 matches instead of EPnP's 5 (for low inlier ratios)
  //! Refine on the RANSAC consensus first, then on the matches that agree with that pose (for mostly wrong matches;
  //! false: one robust refinement over all matches, from the PnP pose)
  bool refineOnConsensus = false;
  double ransacThresholdPx = 2.5; //!< PnP inlier threshold, pixels (sqrt(5.991) at level 0)
  double ransacConfidence = 0.99; //!< PnP RANSAC confidence
  int minInliers = 50;            //!< inliers after refinement to accept (ORB-SLAM2: 50)
  PoseOnlyOptions refinement;     //!< pose-only refinement of the PnP pose
  /*!
    Compare every point of a candidate with every keypoint instead of only those under the same vocabulary node:
    the candidates here are a keyframe and its neighbours, a few thousand points at most (about 1 ms), and
    node-restricted matching loses most of the weaker gradient-pixel descriptors. Measured on 7-Scenes with a
    covered lens: BoW-restricted matching found at most 8 matches per candidate, too few for PnP.
  */
  bool exhaustive = true;
};

//! Outcome of relocalize().
struct RelocalizationResult {
  bool success = false;
  int keyframeId = -1; //!< the keyframe the frame was relocalised against
  SE3d cTw;            //!< pose of the frame
  int matches = 0;     //!< BoW matches with that keyframe (on failure: the most with any candidate)
  int inliers = 0;     //!< after refinement (on failure: the most with any candidate)
  int candidatesTried = 0;
  std::vector<ReprojectionObservation> inlierObservations; //!< the matches the pose was refined on (on success)
  /*!
    On failure, the refined pose with the most inliers that still fell short of minInliers (at least minMatches of
    them): a pose a caller may check against more of the map than the candidate's points (ORB-SLAM2 searches the
    keyframe's points by projection before giving up). -1 when no candidate got that far.
  */
  int nearMissKeyframeId = -1;
  SE3d nearMissCTw;        //!< that pose (identity unless nearMissKeyframeId >= 0)
  int nearMissInliers = 0; //!< its inliers (0 unless nearMissKeyframeId >= 0)
};

//! BoW-restricted matching (ORB-SLAM2 SearchByBoW): pairs (keyframe point, frame keypoint).
VISP_EXPORT std::vector<std::pair<int, int>>
matchByBow(const RelocalizationKeyframe &keyframe, const RelocalizationFrame &frame, const RelocalizerOptions &options);

//! Exhaustive matching with the same rules (best below maxDistance and ratio x second best, one point per keypoint).
VISP_EXPORT std::vector<std::pair<int, int>> matchExhaustive(const RelocalizationKeyframe &keyframe,
                                                             const RelocalizationFrame &frame,
                                                             const RelocalizerOptions &options);
//! Median depth of the points \e wX in the camera \e cTw (0 without points), map units.
VISP_EXPORT double medianDepth(const SE3d &cTw, const std::vector<Eigen::Vector3d> &wX);
//! Median depth of \e r's inlier points in the frame it placed (0 when it has none), map units.
VISP_EXPORT double medianInlierDepth(const RelocalizationResult &r);

//! How far apart two relocalised poses of consecutive frames are.
struct FixAgreement {
  double angleDeg = 0.;   //!< relative rotation
  double depthShare = 0.; //!< camera centre distance over the scene's median depth
  bool agrees = false;    //!< both within the limits below
};
//! Two consecutive fixes agree within this rotation (a hand-held camera turning fast moves a few degrees a frame)...
constexpr double kFixAgreementMaxRotationDeg = 10.;
//! ... and this share of the scene's median depth.
constexpr double kFixAgreementMaxDepthShare = 0.1;
/*!
  Whether two fixes (cMw of consecutive frames) are where a camera could have moved in a frame's time: a wrong PnP
  consensus (a repeated texture, a few accidental matches) lands somewhere else every frame. Measured on the 3-lap
  synthetic loop, after the window emptied during a turn in place: 12 pairs of consecutive right fixes, 0.7-1.8
  degrees and 0.4-2.2 % of the scene depth apart. \e medianDepth <= 0: never agrees.
*/
VISP_EXPORT FixAgreement compareFixes(const SE3d &previousCMw, const SE3d &currentCMw, double medianDepth);

//! Try the candidates in order (see the file comment).
VISP_EXPORT RelocalizationResult relocalize(const RelocalizationFrame &frame,
                                            const std::vector<const RelocalizationKeyframe *> &candidates,
                                            const PinholeIntrinsics &K,
                                            const RelocalizerOptions &options = RelocalizerOptions());
} // namespace hslam

#endif
