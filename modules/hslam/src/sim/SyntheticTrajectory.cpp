#include "sim/SyntheticTrajectory.h"

#include <visp3/hslam/vpHSlamException.h>

#include <visp3/core/vpRotationMatrix.h>
#include <visp3/core/vpTranslationVector.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <string>

namespace hslam
{
namespace
{
constexpr double kTwoPi = 6.283185307179586476925286766559;
constexpr double kDeg = kTwoPi / 360.0;

// Centre of the motion in the room (world frame: x right, y down, z forward; metres). Hand-held height: the
// floor is 1.4 m below y = 0, see SyntheticRenderer.
constexpr double kCentre[3] = {0.0, -0.2, 0.0};

// Shape of the motion before scaling: per axis, amplitude of harmonics 1..3 (metres). An ellipse 1.6 m x 1.2 m in
// the horizontal plane (x, z) with a vertical bob, like a person walking a loop while filming the room.
constexpr double kPosShape[3][SyntheticTrajectory::kHarmonics] = {
    {0.80, 0.15, 0.05}, // x
    {0.05, 0.10, 0.03}, // y (vertical)
    {0.60, 0.15, 0.05}  // z
};
// Euler angle amplitudes (radians): yaw about y, pitch about x, roll about z.
constexpr double kAngShape[3][SyntheticTrajectory::kHarmonics] = {
    {12.0 * kDeg, 4.0 * kDeg, 1.0 * kDeg}, // yaw: pan across the front wall
    {4.0 * kDeg, 2.0 * kDeg, 0.5 * kDeg},  // pitch
    {3.0 * kDeg, 1.0 * kDeg, 0.5 * kDeg}   // roll: hand tremble
};

void rotY(double a, double R[9])
{
  const double c = std::cos(a), s = std::sin(a);
  const double M[9] = {c, 0, s, 0, 1, 0, -s, 0, c};
  std::copy(M, M + 9, R);
}
void rotX(double a, double R[9])
{
  const double c = std::cos(a), s = std::sin(a);
  const double M[9] = {1, 0, 0, 0, c, -s, 0, s, c};
  std::copy(M, M + 9, R);
}
void rotZ(double a, double R[9])
{
  const double c = std::cos(a), s = std::sin(a);
  const double M[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
  std::copy(M, M + 9, R);
}
void mul3(const double A[9], const double B[9], double C[9])
{
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) {
      C[3 * r + c] = A[3 * r] * B[c] + A[3 * r + 1] * B[3 + c] + A[3 * r + 2] * B[6 + c];
    }
  }
}
} // namespace

SyntheticTrajectory::SyntheticTrajectory(unsigned int frameCount, unsigned int seed, double maxStepMetres,
                                         double maxStepRadians, unsigned int laps, bool lookOutward)
    : m_period(static_cast<double>(frameCount > 1 ? frameCount - 1 : 1) / std::max(1u, laps)),
      m_lookOutward(lookOutward)
{
  // Looking outward, yaw turns 2 pi per lap on top of the (small) sinusoids.
  const double turnPerFrame = lookOutward ? kTwoPi / m_period : 0.0;
  if (turnPerFrame > maxStepRadians) {
    throw vpHSlamException(vpHSlamException::invalidArgument,
                           "synthetic trajectory: looking outward, a lap must take at least " +
                               std::to_string(static_cast<int>(std::ceil(kTwoPi / maxStepRadians))) + " frames (got " +
                               std::to_string(m_period) + ")");
  }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> phase(0.0, kTwoPi);
  for (int a = 0; a < 3; ++a) {
    for (int k = 0; k < kHarmonics; ++k) {
      m_posPhase[a][k] = phase(rng);
      m_angPhase[a][k] = phase(rng);
    }
  }
  // The fundamental of x and z a quarter period apart: an ellipse, not a back-and-forth line (which would give
  // no loop and little parallax variety).
  m_posPhase[2][0] = m_posPhase[0][0] + 0.25 * kTwoPi;
  // Pan towards the room centre: yaw opposite to the lateral offset.
  m_angPhase[0][0] = m_posPhase[0][0] + 0.5 * kTwoPi;

  const double omega = kTwoPi / m_period; // radians of phase per frame
  double posBound2 = 0.0, angBound = 0.0;
  for (int a = 0; a < 3; ++a) {
    double posAxis = 0.0;
    for (int k = 0; k < kHarmonics; ++k) {
      posAxis += kPosShape[a][k] * (k + 1) * omega;
      angBound += kAngShape[a][k] * (k + 1) * omega;
    }
    posBound2 += posAxis * posAxis;
  }
  const double posBound = std::sqrt(posBound2);
  const double posScale = posBound > maxStepMetres ? maxStepMetres / posBound : 1.0;
  if (lookOutward) {
    angBound -= kAngShape[0][0] * omega; // no pan across the front wall: the yaw fundamental is the full turn
  }
  const double angBudget = maxStepRadians - turnPerFrame;
  const double angScale = angBound > angBudget ? angBudget / angBound : 1.0;
  for (int a = 0; a < 3; ++a) {
    for (int k = 0; k < kHarmonics; ++k) {
      m_posAmp[a][k] = kPosShape[a][k] * posScale;
      m_angAmp[a][k] = kAngShape[a][k] * angScale;
    }
  }
  if (lookOutward) {
    m_angAmp[0][0] = 0.0;
  }
  m_stepBoundMetres = posBound * posScale;
  m_stepBoundRadians = angBound * angScale + turnPerFrame;
}

SimPose SyntheticTrajectory::pose(double frame) const
{
  // fmod keeps integer frames exact: frame == period gives phase 0, the very same numbers as frame 0.
  const double theta = kTwoPi * (std::fmod(frame, m_period) / m_period);
  SimPose P;
  double ang[3];
  for (int a = 0; a < 3; ++a) {
    double p = 0.0, q = 0.0;
    for (int k = 0; k < kHarmonics; ++k) {
      p += m_posAmp[a][k] * std::sin((k + 1) * theta + m_posPhase[a][k]);
      q += m_angAmp[a][k] * std::sin((k + 1) * theta + m_angPhase[a][k]);
    }
    P.wtc[a] = kCentre[a] + p;
    ang[a] = q;
  }
  if (m_lookOutward) {
    // Forward (the camera's z) along the horizontal offset from the centre: x ~ sin(theta + phase), z ~ cos(...).
    ang[0] += theta + m_posPhase[0][0];
  }
  double Ry[9], Rx[9], Rz[9], Ryx[9];
  rotY(ang[0], Ry);
  rotX(ang[1], Rx);
  rotZ(ang[2], Rz);
  mul3(Ry, Rx, Ryx);
  mul3(Ryx, Rz, P.wRc);
  return P;
}

vpHomogeneousMatrix SyntheticTrajectory::wMc(double frame) const
{
  const SimPose P = pose(frame);
  vpHomogeneousMatrix M;
  for (unsigned int r = 0; r < 3; ++r) {
    for (unsigned int c = 0; c < 3; ++c) {
      M[r][c] = P.wRc[3 * r + c];
    }
    M[r][3] = P.wtc[r];
  }
  return M;
}
} // namespace hslam
