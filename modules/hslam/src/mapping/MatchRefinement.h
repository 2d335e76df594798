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

  The template side (the first image's patch, its gradients and the Gauss-Newton Hessian) depends only on the first
  image and point: the two-view initializer refines the same first-frame keypoints against every new frame, so it
  computes each template once (makeLucasKanadeTemplate) and keeps it while the first frame stays.

  Stateless and thread-safe.
*/
#ifndef HSLAM_MAPPING_MATCH_REFINEMENT_H
#define HSLAM_MAPPING_MATCH_REFINEMENT_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpImage.h>

#include <array>

namespace hslam
{
//! The first image's side of a refinement: an 11x11 patch, its gradients and the inverse-compositional Hessian.
struct LucasKanadeTemplate {
  static constexpr int kHalfPatch = 5; //!< an 11x11 window, the usual KLT size for 640-px images
  static constexpr int kSide = 2 * kHalfPatch + 1;
  static constexpr int kPixels = kSide * kSide;
  std::array<double, kPixels> T{}, gx{}, gy{}; //!< intensities and central-difference gradients, row-major
  double meanT = 0., h00 = 0., h01 = 0., h11 = 0., det = 0.;
};

/*!
  The template of the point at (u1, v1) in \e I1.
  \return false when its patch leaves the image or is textureless (flat or edge-only): no refinement can use it.
*/
VISP_EXPORT bool makeLucasKanadeTemplate(const vpImage<unsigned char> &I1, double u1, double v1,
                                         LucasKanadeTemplate &t);

/*!
  Refine (u2, v2), the position in \e I2 of the point whose template is \e t (see the other overload).
*/
VISP_EXPORT bool refineMatchLucasKanade(const LucasKanadeTemplate &t, const vpImage<unsigned char> &I2, double &u2,
                                        double &v2, double maxShiftPx);

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
