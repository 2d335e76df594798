/*
 * H-SLAM for ViSP.
 */
/*!
  \file TwoViewInitializer.h
  \brief Monocular initialisation from two views: ORB matches to a first frame, essential matrix or homography
  (ORB-SLAM2 model selection), cheirality, triangulation, parallax check.

  What it is for: DSO's coarse photometric initialiser needs many frames of slow motion and fails on fast
  forward motion (KITTI). This initializer keeps a first frame, matches every new frame against it with ORB
  descriptors, and as soon as the geometry is well conditioned returns the relative pose and a sparse set of
  triangulated points in the first frame, which seed the first keyframe (and, through SparseIdepthInterpolator,
  inverse-depth priors for its immature points, refined photometrically afterwards).

  Method (ORB-SLAM2, Mur-Artal et al. 2015, sec. IV "Automatic map initialization", src/Initializer.cc):
  - ORB features (grid-bucketed) in the first frame; per new frame, brute-force Hamming matching with Lowe's
    ratio test and a mutual (cross) check, then each match's second position is refined to sub-pixel accuracy by
    Lucas-Kanade on the patch around the first keypoint (MatchRefinement.h). Matching against the first frame
    rather than tracking frame to frame (pyramidal KLT) keeps one error per match instead of an accumulating drift;
    measured on KITTI 06 it initialises at frame 2 (2.4 m forward) with 0.25 deg rotation and 0.5 deg direction
    error, so KLT (OpenCV's video module, not linked by this module) was not needed. The sub-pixel refinement
    matters: without it (measured with an earlier, fixed-width refinement) rotation errors were 1.3-3x larger
    (Tsukuba 0.18 vs 0.06 deg, KITTI 0.32 vs 0.25 deg).
  - When that attempt fails for too few matches or triangulated points (not for too little parallax, which the next
    frames bring) and at least kMinSeedInliers of its
    matches agree on an essential matrix, the keypoints left unmatched are matched along that matrix's epipolar
    lines (EpipolarMatching.h: the ratio test among a line's few candidates instead of the whole image), refined
    the same way, and the attempt is made again on all matches. Measured on KITTI 06 every 4th frame (4 m between
    frames): the brute-force pass finds 30-70 matches and the first map waited until the 10th frame; see
    docs/hybrid-tracking.md (Decisions).
  - An essential matrix (cv::findEssentialMat, RANSAC) and a homography (cv::findHomography, RANSAC) are both
    fitted and scored with ORB-SLAM2's truncated chi-square scores on all matches; R_H = S_H / (S_H + S_F) above
    kHomographyScoreRatio selects the homography (planar or low-parallax scene), else the essential matrix.
  - Every decomposition of the chosen model (4 for E, up to 4 for H) is tested by triangulating the model's
    inliers; the one with the most points in front of both cameras and within the reprojection threshold wins,
    provided it is unambiguous (no other solution close to it).
  - The chosen (R, t) is refined on all its inliers (Sampson error, Huber width from the residuals' robust
    spread), the points are triangulated again and the checks below repeated on the refined motion.
  - Initialisation needs >= minMatches such points and a median triangulation angle >= minParallaxDeg, else the
    frame is rejected ("waiting"): this rejects pure rotations and static cameras. After maxFramesToInitialize
    rejected frames, or when matches fall below minMatches (the view has moved away from the first frame), the
    current frame becomes the new first frame.

  Output convention: c2Mc1 maps points of the first camera to the current camera; its translation is scaled so
  the median inverse depth of the returned points is Initializer::initialIdepth.

  Threading: not thread-safe; owned and called by the tracking thread during initialisation only.
*/
#ifndef HSLAM_MAPPING_TWO_VIEW_INITIALIZER_H
#define HSLAM_MAPPING_TWO_VIEW_INITIALIZER_H

#include "features/ImagePyramid.h"
#include "features/OrbExtractor.h"
#include "map/Frame.h"
#include "mapping/MatchRefinement.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <opencv2/core.hpp>

#include <vector>

namespace hslam
{
//! A triangulated initial point: pixel in the first frame, its inverse depth there, and its match.
struct InitialPoint {
  double u = 0., v = 0.;       //!< pixel in the first frame
  double idepth = 0.;          //!< inverse depth in the first camera, in the scale of c2Mc1
  double uCur = 0., vCur = 0.; //!< matched pixel in the current frame
  double parallaxDeg = 0.;     //!< triangulation angle, degrees
};

//! The outcome of a successful initialisation.
struct TwoViewInitialization {
  int firstFrameId = -1;              //!< id of the first frame (the points' host)
  int currentFrameId = -1;            //!< id of the frame that initialised
  SE3d c2Mc1;                         //!< first camera -> current camera, translation scaled (see initialIdepth)
  std::vector<InitialPoint> points;   //!< inliers with a reliable depth (parallax >= kMinPointParallaxDeg)
  int numInliers = 0;                 //!< points consistent with the chosen motion (may include low-parallax ones)
  double parallaxDeg = 0.;            //!< median triangulation angle of the inliers, degrees
  bool fromHomography = false;        //!< model selected by the score ratio
  double translationDirSigmaDeg = 0.; //!< statistical uncertainty of the translation direction, degrees
};

//! What happened on the last frame (for logs, tests and tuning).
struct TwoViewAttempt {
  enum Outcome {
    noAttempt,       //!< no frame processed since the first frame
    tooFewMatches,   //!< descriptor matches < minMatches: the first frame was replaced
    tooLittleMotion, //!< median pixel displacement too small to try (static camera)
    modelFailed,     //!< RANSAC or decomposition returned nothing usable
    ambiguousMotion, //!< two decompositions explain the matches about equally well
    tooFewInliers,   //!< triangulated inliers < minMatches
    lowParallax,     //!< median triangulation angle < minParallaxDeg (pure rotation, too short a baseline)
    initialized      //!< success
  };
  Outcome outcome = noAttempt;
  int numMatches = 0;
  int numRefinedMatches = 0; //!< matches moved to sub-pixel accuracy by Lucas-Kanade
  int numInliers = 0;
  double medianFlowPx = 0.;
  double scoreRatioH = 0.; //!< R_H = S_H / (S_H + S_F)
  double parallaxDeg = 0.;
  double translationDirSigmaDeg = 0.; //!< uncertainty of the translation direction (refineRelativePose)
};

//! The ORB extraction the two-view geometry uses: \e params.orbFeatures features a frame, otherwise the defaults.
VISP_EXPORT OrbExtractorOptions twoViewOrbOptions(const vpHSlamParameters::Initializer &params);

/*!
  Two-view monocular initializer (see the file comment for the method).
  \code
  TwoViewInitializer init(params.initializer, K);
  init.setFirstFrame(frame0->raw, frame0->id);
  while (init.addFrame(frame->raw, frame->id) != TwoViewInitializer::initialized) { ... next frame ... }
  const TwoViewInitialization &r = init.result();
  \endcode
*/
class VISP_EXPORT TwoViewInitializer
{
public:
  enum State {
    noFirstFrame, //!< setFirstFrame() not called yet
    waiting,      //!< a first frame is held; the last frame did not initialise
    initialized   //!< result() is valid
  };

  /*!
    \param params : thresholds (copied).
    \param K : pinhole intrinsics of the rectified level-0 images.
    \param orbOptions : feature extraction settings.
    \exception vpHSlamException::invalidArgument for out-of-range parameters.
  */
  TwoViewInitializer(const vpHSlamParameters::Initializer &params, const PinholeIntrinsics &K,
                     const OrbExtractorOptions &orbOptions = OrbExtractorOptions());

  //! Forget everything (state noFirstFrame).
  void reset();
  //! Hold \e I as the first frame (any previous state is dropped). \exception vpHSlamException::invalidImage.
  void setFirstFrame(const vpImage<unsigned char> &I, int frameId);
  void setFirstFrame(const Frame &frame) { setFirstFrame(frame.raw, frame.id); }
  /*!
    Try to initialise from the first frame and \e I. With no first frame yet, \e I becomes it. After success the
    result is kept and further calls return initialized without work until reset() or setFirstFrame().
    \exception vpHSlamException::invalidImage when the size differs from the first frame's.
  */
  State addFrame(const vpImage<unsigned char> &I, int frameId);
  State addFrame(const Frame &frame) { return addFrame(frame.raw, frame.id); }

  State state() const { return m_state; }
  //! \exception vpHSlamException::invalidArgument unless state() == initialized.
  const TwoViewInitialization &result() const;
  const TwoViewAttempt &lastAttempt() const { return m_lastAttempt; }
  int firstFrameId() const { return m_firstId; }
  int firstFrameFeatureCount() const { return static_cast<int>(m_firstKeypoints.size()); }

private:
  struct Match {
    cv::Point2d p1, p2;
    int firstIndex = -1;   //!< keypoint index in the first frame
    int currentIndex = -1; //!< keypoint index in the current frame
    bool refined = false;
  };
  //! First-frame keypoint \e firstIndex paired with current keypoint \e currentIndex of \e keypoints.
  Match matchOf(int firstIndex, int currentIndex, const std::vector<cv::KeyPoint> &keypoints) const;
  void matchToFirst(const std::vector<cv::KeyPoint> &keypoints, const cv::Mat &descriptors,
                    std::vector<Match> &matches) const;
  void refineMatches(const vpImage<unsigned char> &I, std::vector<Match> &matches);
  /*!
    After a failed attempt: an essential matrix from \e matches (when enough of them agree) and the keypoints still
    unmatched paired along its epipolar lines (EpipolarMatching.h), refined, appended. Returns how many were added.
  */
  int addEpipolarMatches(const std::vector<cv::KeyPoint> &keypoints, const cv::Mat &descriptors,
                         const vpImage<unsigned char> &I, std::vector<Match> &matches);
  //! A new first frame: its keypoints' refinement templates are made again, when first needed.
  void forgetTemplates();
  TwoViewAttempt::Outcome solve(const std::vector<Match> &matches, TwoViewAttempt &attempt);
  //! One attempt on \e matches: their counts and solve()'s outcome.
  TwoViewAttempt attemptOn(const std::vector<Match> &matches);

  vpHSlamParameters::Initializer m_params;
  PinholeIntrinsics m_K;
  OrbExtractor m_orb;
  State m_state = noFirstFrame;
  int m_firstId = -1;
  int m_framesSinceFirst = 0;
  unsigned int m_width = 0, m_height = 0;
  vpImage<unsigned char> m_firstImage;
  std::vector<cv::KeyPoint> m_firstKeypoints;
  cv::Mat m_firstDescriptors;
  //! Per first-frame keypoint: its Lucas-Kanade template, made at its first match and kept for later frames (the
  //! same keypoints are refined against every frame); state 0 = not made yet, 1 = usable, -1 = unusable.
  std::vector<LucasKanadeTemplate> m_templates;
  std::vector<signed char> m_templateState;
  TwoViewInitialization m_result;
  TwoViewAttempt m_lastAttempt;
};
} // namespace hslam

#endif
