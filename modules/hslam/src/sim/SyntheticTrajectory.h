// Smooth closed camera trajectory for the synthetic sequences (hand-held-like, returns to its start).
#ifndef HSLAM_SIM_SYNTHETIC_TRAJECTORY_H
#define HSLAM_SIM_SYNTHETIC_TRAJECTORY_H

#include <visp3/core/vpHomogeneousMatrix.h>

namespace hslam
{
//! A camera pose as plain numbers: wRc row-major (camera-to-world rotation) and wtc (camera centre, metres).
struct SimPose {
  double wRc[9];
  double wtc[3];
};

/*!
  Closed, smooth trajectory: positions and Euler angles are sums of sinusoids whose fundamental period is the whole
  sequence (frameCount - 1 frames), so frame frameCount - 1 has exactly the pose of frame 0 (a loop).

  The harmonics' amplitudes are fixed shapes (an ellipse in the horizontal plane with a little vertical bob, small
  pan/tilt/roll); their phases come from the seed. Amplitudes are then scaled down, if needed, so that an analytic
  upper bound of the motion between two consecutive frames stays below maxStepMetres and maxStepRadians: the bound
  is sum_k A_k * k * omega per axis (derivative of a sinusoid), combined with the Euclidean norm for translation
  and with the triangle inequality on SO(3) for the three elementary rotations.

  Threading: immutable after construction.
*/
class SyntheticTrajectory
{
public:
  //! Number of harmonics per coordinate.
  static constexpr int kHarmonics = 3;

  /*!
    \param frameCount : frames of the sequence (>= 2).
    \param seed : selects the phases.
    \param maxStepMetres, maxStepRadians : bounds on the motion between consecutive frames.
    \param laps : times the loop is driven (>= 1); the period is (frameCount - 1) / laps frames, so with laps
    dividing frameCount - 1 every lap starts exactly at the pose of frame 0.
    \param lookOutward : false (default): the camera pans across the front wall; true: it looks away from the
    centre of its loop, turning a full circle per lap, so it films the four walls in turn and what it saw first
    leaves the view (a loop that a sliding window cannot close by itself). The full turn cannot be scaled down:
    a lap must then take at least 2 pi / maxStepRadians frames.
    \exception vpHSlamException::invalidArgument when a lap is too short for lookOutward.
  */
  SyntheticTrajectory(unsigned int frameCount, unsigned int seed, double maxStepMetres, double maxStepRadians,
                      unsigned int laps = 1, bool lookOutward = false);

  //! Pose at a (possibly fractional) frame index; integer indices are exactly periodic.
  SimPose pose(double frame) const;
  //! Same as pose(), as a ViSP camera-to-world transform.
  vpHomogeneousMatrix wMc(double frame) const;

  //! Analytic upper bounds of the motion per frame after scaling (metres, radians).
  double stepBoundMetres() const { return m_stepBoundMetres; }
  double stepBoundRadians() const { return m_stepBoundRadians; }

private:
  double m_period; //!< loop period in frames ((frameCount - 1) / laps)
  bool m_lookOutward = false;
  double m_posAmp[3][kHarmonics], m_posPhase[3][kHarmonics];
  double m_angAmp[3][kHarmonics], m_angPhase[3][kHarmonics];
  double m_stepBoundMetres, m_stepBoundRadians;
};
} // namespace hslam

#endif
