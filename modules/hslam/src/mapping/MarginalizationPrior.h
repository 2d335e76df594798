/*
 * H-SLAM for ViSP.
 */
/*!
  \file MarginalizationPrior.h
  \brief The marginalisation prior (H, b) of the sliding window on the keyframes' pose + affine states.

  What it is for: when a keyframe leaves the photometric window (DSO, Engel et al. 2018, sec. 3.2 and 2.3), its
  points and its own 8 states are eliminated by Schur complements; what they said about the remaining keyframes
  is kept as a quadratic prior
      E_M(x) = 2 b^T D + D^T H D,   D = chart deviation of each keyframe from its linearisation point,
  (the factor 2 matches the window's convention E ~ E0 + 2 b^T d + d^T H d with H = J^T W J, b = J^T W r).

  First-estimate Jacobians (FEJ): a keyframe whose states enter the prior gets a linearisation point
  (state_zero) that never moves afterwards. Its deviation is D = (log(cMw cMw0^-1), a - a0, b - b0) (left chart,
  the same perturbation as the window's Jacobians); the prior's gradient at the current state is b + H D.
  New information computed at the current state (Jacobian J, gradient g) is moved to the existing linearisation
  points before it is added (DSO's fixLinearization: b0 = g - H D), so the prior stays a single quadratic.

  Frame indices follow the window order (index 0 = oldest keyframe); addFrame() appends, removeFrame()
  Schur-complements a keyframe out (or simply drops it when it was the fixed gauge keyframe: an infinitely
  constrained state contributes no Schur term).

  Threading: not thread-safe; owned by the WindowOptimizer of the mapping thread.
*/
#ifndef HSLAM_MAPPING_MARGINALIZATION_PRIOR_H
#define HSLAM_MAPPING_MARGINALIZATION_PRIOR_H

#include "mapping/PhotometricResidual.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <vector>

namespace hslam
{
//! Current (or linearisation) state of one keyframe: world-to-camera pose and affine (a, b).
struct KeyframeState {
  SE3d cMw;
  double a = 0.;
  double b = 0.;
};

class VISP_EXPORT MarginalizationPrior
{
public:
  //! Number of keyframes the prior spans (equals the window size).
  int numFrames() const { return static_cast<int>(m_linearized.size()); }
  //! True once some information was marginalised (before that H = 0, b = 0).
  bool hasInformation() const { return m_hasInformation; }
  //! Append a keyframe without information (zero rows and columns).
  void addFrame();
  //! Whether keyframe i has a fixed linearisation point (its states are connected to the prior).
  bool isLinearized(int i) const { return m_linearized[static_cast<size_t>(i)]; }
  //! Linearisation point of keyframe i (valid when isLinearized(i)).
  const KeyframeState &linearizationPoint(int i) const { return m_zero[static_cast<size_t>(i)]; }

  /*!
    Deviation D of the current states from the linearisation points (zero for keyframes without one).
    \param states : current state of every keyframe, window order.
  */
  Eigen::VectorXd deviation(const std::vector<KeyframeState> &states) const;

  /*!
    Add information (Hadd, gAdd) linearised at the CURRENT states. Keyframes touched by Hadd (non-zero diagonal
    block) without a linearisation point get the current state as theirs; for the others the gradient is moved to
    their linearisation point (FEJ).
  */
  void add(const Eigen::MatrixXd &Hadd, const Eigen::VectorXd &gAdd, const std::vector<KeyframeState> &states);

  /*!
    Eliminate keyframe i: Schur complement of its 8 states, or, when \e fixedGauge, drop them (the keyframe was
    held fixed, so what it said about the others is already relative to a known state).
  */
  void removeFrame(int i, bool fixedGauge);

  //! Energy E_M and its gradient/Hessian (b + H D, H) at the current states.
  double energy(const std::vector<KeyframeState> &states) const;
  Eigen::VectorXd gradient(const std::vector<KeyframeState> &states) const;

  const Eigen::MatrixXd &H() const { return m_H; }
  const Eigen::VectorXd &b() const { return m_b; }

private:
  Eigen::MatrixXd m_H;
  Eigen::VectorXd m_b;
  std::vector<bool> m_linearized;
  std::vector<KeyframeState> m_zero;
  bool m_hasInformation = false;
};

//! Left-chart deviation (log(cMw cMw0^-1), a - a0, b - b0) of a state from a linearisation point.
VISP_EXPORT Vec8d stateDeviation(const KeyframeState &current, const KeyframeState &zero);
} // namespace hslam

#endif
