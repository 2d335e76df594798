// Monocular scale and world frame from known poses: the Sim(3) between a SLAM trajectory and the true one.
// Header-only and ViSP-core-only, so the tests can check it on exact data without the servo program.
#ifndef HSLAM_TUTORIAL_SIM3_FROM_POSES_H
#define HSLAM_TUTORIAL_SIM3_FROM_POSES_H

#include <visp3/core/vpColVector.h>
#include <visp3/core/vpException.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpRotationMatrix.h>
#include <visp3/core/vpThetaUVector.h>
#include <visp3/core/vpTranslationVector.h>

#include <cmath>
#include <vector>

namespace hslam_servo
{
//! A similarity p_g = scale gRe p_e + gte between the SLAM world e and the simulator's world g.
struct Sim3 {
  vpHomogeneousMatrix gMe; //!< rotation and translation
  double scale = 0.;       //!< metres per SLAM unit
  double rmseMetres = 0.;  //!< residual distance of the camera centres used, metres
};

/*!
  The Sim(3) mapping SLAM poses eMc_i onto known simulator poses gMc_i. Rotation first, from the orientations: each
  pair gives gRe_i = gRc_i eRc_i^T, and gRe is their mean in the tangent space at the first (the spread is a few
  hundredths of a degree, where this equals the chordal L2 mean). Then scale and translation in closed form for that
  rotation (least squares on the camera centres): s = sum (g_i - g) . gRe (e_i - e) / sum |e_i - e|^2, t = g - s gRe e,
  with g and e the centroids. Orientations fix the rotation better than the positions of a short path do (Umeyama
  on positions only: the rotation error is about the position noise over the path's extent, a few tenths of a
  degree here), and the servo's rotation error at the goal is exactly this rotation's error.
*/
inline Sim3 alignSim3(const std::vector<vpHomogeneousMatrix> &eMc, const std::vector<vpHomogeneousMatrix> &gMc)
{
  const size_t n = eMc.size();
  if (n < 2 || gMc.size() != n) {
    throw vpException(vpException::dimensionError, "Sim(3) from poses: need two lists of the same size, at least 2");
  }
  const vpRotationMatrix gRe0 = gMc[0].getRotationMatrix() * eMc[0].getRotationMatrix().inverse();
  vpColVector meanLog(3, 0.);
  for (size_t i = 0; i < n; ++i) {
    const vpRotationMatrix gRei = gMc[i].getRotationMatrix() * eMc[i].getRotationMatrix().inverse();
    meanLog += vpColVector(vpThetaUVector(gRe0.inverse() * gRei)) / static_cast<double>(n);
  }
  const vpRotationMatrix gRe = gRe0 * vpRotationMatrix(vpThetaUVector(meanLog[0], meanLog[1], meanLog[2]));

  vpColVector gMean(3, 0.), eMean(3, 0.);
  for (size_t i = 0; i < n; ++i) {
    gMean += vpColVector(gMc[i].getTranslationVector()) / static_cast<double>(n);
    eMean += vpColVector(gRe * eMc[i].getTranslationVector()) / static_cast<double>(n);
  }
  double cross = 0., spread = 0.;
  for (size_t i = 0; i < n; ++i) {
    const vpColVector g = vpColVector(gMc[i].getTranslationVector()) - gMean;
    const vpColVector e = vpColVector(gRe * eMc[i].getTranslationVector()) - eMean;
    cross += vpColVector::dotProd(g, e);
    spread += e.sumSquare();
  }
  if (!(spread > 0.)) {
    throw vpException(vpException::badValue, "Sim(3) from poses: the SLAM camera centres do not move, no scale");
  }
  Sim3 sim3;
  sim3.scale = cross / spread;
  const vpColVector gte = gMean - sim3.scale * eMean;
  sim3.gMe = vpHomogeneousMatrix(vpTranslationVector(gte[0], gte[1], gte[2]), gRe);
  double sum = 0.;
  for (size_t i = 0; i < n; ++i) {
    const vpColVector g(gMc[i].getTranslationVector());
    const vpColVector e = sim3.scale * vpColVector(gRe * eMc[i].getTranslationVector()) + gte;
    sum += (g - e).sumSquare();
  }
  sim3.rmseMetres = std::sqrt(sum / n);
  return sim3;
}

/*!
  A SLAM pose eMc (camera to SLAM world e, SLAM units) in the simulator's world g, through the Sim(3)
  p_g = s gRe p_e + gte: orientation gRe eRc, centre s gRe etc + gte.
*/
inline vpHomogeneousMatrix toWorld(const Sim3 &sim3, const vpHomogeneousMatrix &eMc)
{
  const vpRotationMatrix gRe = sim3.gMe.getRotationMatrix();
  const vpRotationMatrix gRc = gRe * eMc.getRotationMatrix();
  const vpTranslationVector gtc = gRe * (eMc.getTranslationVector() * sim3.scale) + sim3.gMe.getTranslationVector();
  return vpHomogeneousMatrix(gtc, gRc);
}
} // namespace hslam_servo

#endif
