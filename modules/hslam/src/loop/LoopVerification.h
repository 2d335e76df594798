/*
 * H-SLAM for ViSP.
 */
/*!
  \file LoopVerification.h
  \brief Geometric verification of a loop candidate (paper sec. 3.4): 3D-3D matches between the two ends of the
  loop, widened through each end's co-visible keyframes, Horn's Sim(3) in RANSAC, guided matching, refinement.

  The two sides: side A is the keyframe that asks (the query) with its best co-visible stored keyframes, side B the
  candidate with its own; every point of a side is expressed in its first keyframe's camera through the stored
  poses (a side is one rigid piece of map). Steps:
  1. descriptor matching keyframe by keyframe (each A keyframe against each B keyframe, matchLoopPoints: best
     Hamming distance within maxDistance and below ratio x second best), an A point and a B point each used once
     (the closest pair wins); matched keyframe by keyframe, the ratio test is not spoilt by the same place seen
     twice on one side;
  2. with at least minMatches of them, the Sim(3) RANSAC (Sim3Solver.h: 3 matches per hypothesis, inliers by
     reprojection in both images);
  3. guided matching: every B point mapped through that similarity into the query's camera is paired with the
     unmatched A point closest in descriptor within a radius (level-scaled) of its projection;
  4. the similarity refined on all its matches, and the inliers counted again; accepted with minInliers, of which
     at least half between the query keyframe and the candidate themselves (the neighbours widen, they do not stand
     in for the loop's two ends).

  Threading: pure functions (the RANSAC is seeded from the options: deterministic).
*/
#ifndef HSLAM_LOOP_LOOP_VERIFICATION_H
#define HSLAM_LOOP_LOOP_VERIFICATION_H

#include "loop/LoopDetector.h"
#include "loop/LoopFeatures.h"
#include "loop/Sim3Solver.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>

#include <vector>

namespace hslam
{
//! One keyframe of a side: its loop features and its pose relative to the side's first keyframe.
struct LoopSideKeyframe {
  const LoopKeyframe *features = nullptr;
  SE3d sideMkeyframe; //!< maps this keyframe's camera into the side's first keyframe's camera
};

//! Settings (vpHSlamParameters::Loop).
struct LoopVerificationOptions {
  int maxDistance = 50;       //!< Hamming distance accepted at most
  double ratio = 0.75;        //!< best below ratio x second best
  int minMatches = 20;        //!< descriptor matches needed to try the Sim(3)
  int minInliers = 40;        //!< inliers needed after refinement (at least half between the two ends)
  double thresholdPx = 3.035; //!< inlier reprojection error in each image, pixels
  double guidedRadiusPx = 8.; //!< guided matching radius at level 0 (times 1.2^level), pixels
  unsigned int seed = 1;      //!< of the RANSAC sampler
};

//! What verifyLoopSides() found.
struct LoopVerification {
  int matches = 0;        //!< descriptor matches of step 1
  int guidedMatches = 0;  //!< added by step 3
  int centralInliers = 0; //!< inliers between the query keyframe itself and the candidate itself
  Sim3Estimate estimate;  //!< S21 maps side B (candidate camera) into side A (query camera); success: accepted
  std::vector<LoopPointMatch> inliers; //!< the accepted similarity's inlier matches
};

/*!
  Verify a loop between side A (\e query, first entry the querying keyframe) and side B (\e candidate, first entry
  the candidate); see the file comment. An empty side fails.
*/
VISP_EXPORT LoopVerification verifyLoopSides(const std::vector<LoopSideKeyframe> &query,
                                             const std::vector<LoopSideKeyframe> &candidate, const PinholeIntrinsics &K,
                                             const LoopVerificationOptions &options);
} // namespace hslam

#endif
