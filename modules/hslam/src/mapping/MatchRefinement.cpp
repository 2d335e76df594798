/*
 * H-SLAM for ViSP.
 */
#include "mapping/MatchRefinement.h"

#include <array>
#include <cmath>

namespace hslam
{
namespace
{
constexpr int kHalfPatch = LucasKanadeTemplate::kHalfPatch;
constexpr int kPatchPixels = LucasKanadeTemplate::kPixels;
constexpr int kMaxIterations = 10;
//! Stop when the update is below this, pixels.
constexpr double kConvergedStepPx = 0.01;
//! Minimum determinant of the 2x2 structure tensor per pixel^2 (grey levels^4): rejects flat and edge-only patches.
constexpr double kMinStructureDetPerPixelSq = 4.;
//! Largest RMS grey-level difference after alignment (JPEG and small affine warps leave a few levels).
constexpr double kMaxResidualRms = 20.;

double bilinear(const vpImage<unsigned char> &I, double u, double v)
{
  const int iu = static_cast<int>(u), iv = static_cast<int>(v);
  const double du = u - iu, dv = v - iv;
  const unsigned char *r0 = I[static_cast<unsigned int>(iv)] + iu;
  const unsigned char *r1 = I[static_cast<unsigned int>(iv + 1)] + iu;
  return (1. - dv) * ((1. - du) * r0[0] + du * r0[1]) + dv * ((1. - du) * r1[0] + du * r1[1]);
}

bool patchInside(const vpImage<unsigned char> &I, double u, double v)
{
  // One extra pixel for the central-difference gradients and the bilinear neighbour.
  const double margin = kHalfPatch + 2;
  return u >= margin && v >= margin && u < I.getWidth() - margin && v < I.getHeight() - margin;
}
} // namespace

bool makeLucasKanadeTemplate(const vpImage<unsigned char> &I1, double u1, double v1, LucasKanadeTemplate &t)
{
  if (!patchInside(I1, u1, v1)) {
    return false;
  }
  // Inverse compositional: the template's gradients and Hessian are computed once.
  t.meanT = t.h00 = t.h01 = t.h11 = 0.;
  int k = 0;
  for (int dy = -kHalfPatch; dy <= kHalfPatch; ++dy) {
    for (int dx = -kHalfPatch; dx <= kHalfPatch; ++dx, ++k) {
      const double u = u1 + dx, v = v1 + dy;
      t.T[k] = bilinear(I1, u, v);
      t.gx[k] = 0.5 * (bilinear(I1, u + 1., v) - bilinear(I1, u - 1., v));
      t.gy[k] = 0.5 * (bilinear(I1, u, v + 1.) - bilinear(I1, u, v - 1.));
      t.meanT += t.T[k];
      t.h00 += t.gx[k] * t.gx[k];
      t.h01 += t.gx[k] * t.gy[k];
      t.h11 += t.gy[k] * t.gy[k];
    }
  }
  t.meanT /= kPatchPixels;
  t.det = t.h00 * t.h11 - t.h01 * t.h01;
  return t.det >= kMinStructureDetPerPixelSq * kPatchPixels * kPatchPixels;
}

bool refineMatchLucasKanade(const vpImage<unsigned char> &I1, double u1, double v1, const vpImage<unsigned char> &I2,
                            double &u2, double &v2, double maxShiftPx)
{
  LucasKanadeTemplate t;
  return makeLucasKanadeTemplate(I1, u1, v1, t) && refineMatchLucasKanade(t, I2, u2, v2, maxShiftPx);
}

bool refineMatchLucasKanade(const LucasKanadeTemplate &t, const vpImage<unsigned char> &I2, double &u2, double &v2,
                            double maxShiftPx)
{
  if (!patchInside(I2, u2, v2)) {
    return false;
  }
  const std::array<double, kPatchPixels> &T = t.T, &gx = t.gx, &gy = t.gy;
  const double meanT = t.meanT, h00 = t.h00, h01 = t.h01, h11 = t.h11, det = t.det;
  const double u2Start = u2, v2Start = v2;
  double u = u2, v = v2, residualSq = 0.;
  bool converged = false;
  for (int it = 0; it < kMaxIterations && !converged; ++it) {
    if (!patchInside(I2, u, v)) {
      return false;
    }
    std::array<double, kPatchPixels> I;
    double meanI = 0.;
    int k = 0;
    for (int dy = -kHalfPatch; dy <= kHalfPatch; ++dy) {
      for (int dx = -kHalfPatch; dx <= kHalfPatch; ++dx, ++k) {
        I[k] = bilinear(I2, u + dx, v + dy);
        meanI += I[k];
      }
    }
    meanI /= kPatchPixels;
    double b0 = 0., b1 = 0.;
    residualSq = 0.;
    for (k = 0; k < kPatchPixels; ++k) {
      const double e = (I[k] - meanI) - (T[k] - meanT);
      b0 += gx[k] * e;
      b1 += gy[k] * e;
      residualSq += e * e;
    }
    const double du = (h11 * b0 - h01 * b1) / det;
    const double dv = (h00 * b1 - h01 * b0) / det;
    u -= du;
    v -= dv;
    converged = du * du + dv * dv < kConvergedStepPx * kConvergedStepPx;
  }
  if (!converged || std::hypot(u - u2Start, v - v2Start) > maxShiftPx ||
      residualSq > kMaxResidualRms * kMaxResidualRms * kPatchPixels) {
    return false;
  }
  u2 = u;
  v2 = v;
  return true;
}
} // namespace hslam
