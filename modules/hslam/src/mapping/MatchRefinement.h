/*
 * H-SLAM for ViSP.
 */
/*!
  \file MatchRefinement.h
  \brief Sub-pixel refinement of a feature match by translational Lucas-Kanade on the full-resolution images.

  What it is for: ORB keypoints found on coarse pyramid octaves carry the octave's quantisation (1.2^octave
  pixels) and FAST corners are integer pixels. Two-view geometry with a short baseline (hand-held start) is
  sensitive to that noise: the rotation absorbs part of the translation. Aligning the 11x11 patch around the
  first-frame keypoint in the second image (inverse-compositional Lucas-Kanade, Baker & Matthews 2004, translation
  only, brightness offset removed) gives the second position of the SAME image point at sub-pixel accuracy.

  Stateless and thread-safe.
*/
#ifndef HSLAM_MAPPING_MATCH_REFINEMENT_H
#define HSLAM_MAPPING_MATCH_REFINEMENT_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

namespace hslam
{
/*!
  Refine (u2, v2), the position in \e I2 of the point at (u1, v1) in \e I1.
  \param maxShiftPx : the refined position may move at most this far from the input one, pixels.
  \return false (and (u2, v2) unchanged) when the patch leaves an image, is textureless, does not converge, moves
  too far or still differs too much after alignment.
*/
VISP_EXPORT bool refineMatchLucasKanade(const vpImage<unsigned char> &I1, double u1, double v1,
                                        const vpImage<unsigned char> &I2, double &u2, double &v2, double maxShiftPx);
} // namespace hslam

#endif
