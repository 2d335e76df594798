/*
 * H-SLAM for ViSP.
 */
// The per-pixel weights of the direct photometric error, shared by tracking, point tracing and window
// optimisation so that every stage weighs a residual the same way. Header only, float or double.
#ifndef HSLAM_COMMON_ROBUST_WEIGHTS_H
#define HSLAM_COMMON_ROBUST_WEIGHTS_H

namespace hslam
{
/*!
  Huber weight of a residual of magnitude \e absResidual: 1 inside the threshold, threshold / |r| outside
  (DSO: hw = |r| < setting_huberTH ? 1 : setting_huberTH / |r|; at |r| = threshold both branches give 1).
*/
template <typename T> inline T huberWeight(T absResidual, T threshold)
{
  return absResidual <= threshold ? T(1) : threshold / absResidual;
}

/*!
  DSO's gradient-dependent pixel weight c^2 / (c^2 + |grad I|^2): strong edges count less, they are less reliable
  under small misalignments. \e cSq is c^2, \e gradientSqNorm is |grad I|^2.
*/
template <typename T> inline T gradientWeight(T cSq, T gradientSqNorm)
{
  return cSq / (cSq + gradientSqNorm);
}
} // namespace hslam

#endif
