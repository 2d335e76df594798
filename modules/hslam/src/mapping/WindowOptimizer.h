/*
 * H-SLAM for ViSP.
 */
/*!
  \file WindowOptimizer.h
  \brief Sliding-window photometric bundle adjustment with marginalisation (DSO's back end, Engel et al. 2018).

  What it is for: the mapping thread's optimiser of the active window. States: for every window keyframe its
  world-to-camera pose (left-perturbed SE(3)) and affine brightness (a, b), and the inverse depth of every ACTIVE
  point hosted in a window keyframe. Residuals: each active point against every other window keyframe
  (PhotometricResidual.h). Solver: Levenberg-Marquardt (Marquardt damping H_ii (1 + lambda), steps accepted when
  the total energy decreases), inverse depths eliminated by the Schur complement (1x1 blocks), the reduced
  (8 n x 8 n) keyframe system solved densely (Jacobi-scaled LDLT), inverse depths back-substituted.

  Gauge (monocular photometric BA has 7 + 1 free directions: pose, scale and the common log-gain a):
  - while the first keyframe ever added is in the window, its 8 states are held fixed (pose and affine gauge);
  - when it is marginalised it is dropped (a fixed state passes no Schur term), so the prior keeps the remaining
    keyframes tied to it: from then on the prior carries the pose and affine gauge (as DSO's first-frame prior
    does once marginalised);
  - scale is not observable from photometric residuals: each step is constrained orthogonal to the scale direction
    (all translations scaled about the gauge keyframe's centre), with a rank-one term in the Jacobi-scaled system
    and a final projection (DSO orthogonalises its steps against the same null space). Exception: with
    globalMap.anchors, re-used points anchored to stored keyframes (AnchorResidual.h) measure the scale, and with
    globalMap.anchorMinForScale of them in the window the step is left free.

  Marginalisation (marginalizeKeyframe): the keyframe's points with an inverse-depth Hessian above
  mapper.minIdepthHessianMarginalize are Schur-complemented into the prior, the others dropped; residuals of
  other points into the keyframe are dropped; then the keyframe's 8 states are Schur-complemented out of the
  prior. First-estimate Jacobians: see MarginalizationPrior.h. Residual Jacobians are evaluated at the current
  state (basalt-style FEJ restricted to the prior), which keeps LM's convergence of the non-linear problem.

  Data ownership: poses and affine live in Frame (cMw, affine), inverse depths in MapPoint (idepth, idepthVar,
  status); the optimiser reads them at the start of optimize() and writes them back at the end. Everything else
  (linearisation points, residual lists, Hessian blocks) stays here. Points are found by scanning the window
  keyframes' Keyframe::points for status active (new ones are registered, ones whose status changed are released).

  Threading: not thread-safe; the mapping thread owns it. The per-point passes of optimize() and reducedSystem()
  (linearisation, Schur complement, trial energy) are range-based (see WindowLinearization.h) and split over an
  owned WorkerPool of system.workerThreads threads plus the calling thread: one accumulator per participant,
  merged in participant order, so results are deterministic for a given thread count (sums are only reordered
  between different counts). With workerThreads = 0 the passes run in the caller exactly as a single range.
*/
#ifndef HSLAM_MAPPING_WINDOW_OPTIMIZER_H
#define HSLAM_MAPPING_WINDOW_OPTIMIZER_H

#include "common/WorkerPool.h"
#include "map/GlobalMap.h"
#include "map/Keyframe.h"
#include "mapping/MarginalizationPrior.h"
#include "mapping/WindowLinearization.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <array>
#include <memory>
#include <vector>

namespace hslam
{
//! What optimize() did.
struct OptimizationSummary {
  int iterations = 0; //!< LM iterations run (accepted + rejected steps)
  int acceptedSteps = 0;
  bool converged = false;    //!< stopped because the step became small
  double initialEnergy = 0.; //!< total energy (photometric + priors) before
  double finalEnergy = 0.;   //!< total energy after
  //! Photometric part of finalEnergy (the marginalisation prior's energy is relative: it can be negative).
  double finalPhotometricEnergy = 0.;
  std::vector<double> acceptedEnergies; //!< energy after each accepted step (strictly decreasing)
  double finalLambda = 0.;
  int activePoints = 0;       //!< points optimised
  int inlierResiduals = 0;    //!< at the final state
  int removedResiduals = 0;   //!< outlier residuals removed at the end
  int outlierPoints = 0;      //!< points flagged PointStatus::outlier at the end
  double totalMs = 0.;        //!< wall time of optimize()
  double msPerIteration = 0.; //!< (linearisation + solve + trial energy) per iteration
};

//! Result of optimising one new point's inverse depth against the window (activation, DSO optimizeImmaturePoint).
struct PointActivationResult {
  bool accepted = false;     //!< Hessian >= mapper.minIdepthHessianActivate, positive depth, >= 1 inlier residual
  double idepth = 0.;        //!< optimised inverse depth
  double idepthHessian = 0.; //!< sum over inlier residuals of J^T W J (1 / variance proxy)
  int inlierResiduals = 0;
  double energy = 0.; //!< clamped robust energy at the result
};

class VISP_EXPORT WindowOptimizer
{
public:
  /*!
    Takes mapper.* (window, LM, marginalisation), tracker.* (Huber, gradient weight, outliers, affine priors) and
    system.workerThreads (threads of the per-point passes; 0 = all in the caller).
  */
  explicit WindowOptimizer(const vpHSlamParameters &params);

  /*!
    Choose the affine priors: tracker.affinePrior{A,B}Calibrated when the images are photometrically calibrated
    (a fixed by the exposures), tracker.affinePrior{A,B} otherwise (default).
  */
  void setPhotometricallyCalibrated(bool calibrated);

  /*!
    Append a keyframe (newest). Its level-0 intrinsics are the camera's; active points already in the window get a
    residual into it, and its own active points are registered at the next optimize().
    \exception vpHSlamException::invalidArgument when the window would exceed kMaxWindowKeyframes or the keyframe
    has no pyramid.
  */
  void addKeyframe(const KeyframePtr &keyframe);

  /*!
    Run up to \e maxIterations LM iterations (at least mapper.minOptimizationIterations unless nothing to do).
    Writes back Frame::cMw / affine of the window keyframes and MapPoint::idepth / idepthVar; points with more than
    mapper.outlierResidualFraction of their residuals removed as outliers get PointStatus::outlier.
  */
  OptimizationSummary optimize(int maxIterations);

  /*!
    Remove a keyframe from the window (see the file comment). Its points become PointStatus::marginalized
    (idepth, idepthVar kept), and Keyframe::inWindow is cleared.
    \exception vpHSlamException::invalidArgument when the id is not in the window.
  */
  void marginalizeKeyframe(int keyframeId);

  /*!
    DSO's flagFramesForMarginalization on the current window (newest keyframe included): every keyframe with fewer
    than mapper.minPointsFractionKept of its points still in play (active + immature) or whose brightness ratio
    to the newest exceeds mapper.maxAffineChangeMarginalize in |log|, while more than mapper.minWindowSize stay;
    then, if the window still exceeds mapper.windowSize, the one maximising DSO's distance score (never the two
    newest nor keyframe 0). Returns keyframe ids.
  */
  std::vector<int> keyframesToMarginalize() const;

  /*!
    For the connectivity graph, before marginalizeKeyframe(): the pose-pose information of window keyframe
    \e keyframeId with every other window keyframe it shares inlier residuals with. Re-uses the last optimize()'s
    linearisation while no keyframe was added or marginalised since (else linearises all points once), so the
    mapper asks for every keyframe it will marginalise right after optimize().
  */
  std::vector<PairInformation> pairInformation(int keyframeId);

  /*!
    Optimise the inverse depth of a candidate point hosted in window keyframe \e hostKeyframeId against all other
    window keyframes, poses fixed (DSO optimizeImmaturePoint). Does not add the point. With \e priorWeight > 0
    (a re-activated global point) the energy gets priorWeight (idepth - priorIdepth)^2 and the returned Hessian
    includes priorWeight; acceptance still asks the photometric Hessian alone for mapper.minIdepthHessianActivate.
  */
  PointActivationResult optimizeNewPoint(int hostKeyframeId, double u, double v, double idepth,
                                         const std::array<float, kPatternSize> &patch,
                                         const std::array<float, kPatternSize> &weight, int iterations,
                                         double priorIdepth = 0., double priorWeight = 0.) const;

  //! Inverse-depth Hessian of such a candidate at \e idepth (compare with mapper.minIdepthHessianActivate).
  double idepthHessian(int hostKeyframeId, double u, double v, double idepth,
                       const std::array<float, kPatternSize> &patch,
                       const std::array<float, kPatternSize> &weight) const;

  int numKeyframes() const { return static_cast<int>(m_frames.size()); }
  //! Window keyframes, oldest first.
  std::vector<KeyframePtr> keyframes() const;
  int numActivePoints() const { return static_cast<int>(m_points.size()); }
  const MarginalizationPrior &prior() const { return m_prior; }

  /*!
    For tests and diagnostics: the reduced (points eliminated) keyframe system at the current states, undamped,
    WITHOUT any gauge handling: H (8n x 8n) and gradient b (E ~ E0 + 2 b^T d + d^T H d). With \e withPriors, the
    affine priors and the marginalisation prior are included. Registers points first.
  */
  void reducedSystem(Eigen::MatrixXd &H, Eigen::VectorXd &b, bool withPriors = false);
  //! Total energy (photometric + affine priors + marginalisation prior) at the current states.
  double totalEnergy();

private:
  struct WindowFrame {
    KeyframePtr kf;
    size_t scannedPoints = 0; //!< Keyframe::points[0..scannedPoints) were looked at by syncPoints()
    KeyframeState backup;
  };

  void syncStatesAndPoints();
  void registerPoint(int host, int pointIndex);
  void prepareContext();
  void linearizeAll(const std::vector<int> &order, WindowAccumulator &acc);
  //! Adds the Schur terms of points \e order (damping \e lambda) to acc.Hsc / acc.bsc (sized by the caller).
  void schurAll(const std::vector<int> &order, double lambda, WindowAccumulator &acc);
  double energyAll(const std::vector<int> &order);
  void assembleFullSystem(const WindowAccumulator &acc, Eigen::MatrixXd &H, Eigen::VectorXd &b) const;
  double priorEnergy() const;
  void addPriors(Eigen::MatrixXd &H, Eigen::VectorXd &b) const;
  bool solveStep(double lambda, Eigen::VectorXd &dx);
  void applyStep(const Eigen::VectorXd &dx, double lambda);
  void backupStates();
  void restoreStates();
  double stepNorm(const Eigen::VectorXd &dx) const;
  int gaugeFixedIndex() const;
  Eigen::VectorXd scaleDirection() const;
  void writeBack();
  void finalizeOutliers(OptimizationSummary &summary);
  void removePointsIf(const std::vector<char> &remove);
  void remapAfterFrameRemoval(int removed);
  //! marginalizeKeyframe(), step 1: the well-constrained points of window keyframe \e idx, Schur-complemented
  //! into the prior with the keyframe's affine prior.
  void marginalizeHostedPoints(int idx);
  //! marginalizeKeyframe(), step 2: points hosted by \e idx, or observed only by it, leave the window.
  void removePointsWithKeyframe(int idx);
  //! marginalizeKeyframe(), step 3: the keyframe's states leave the prior and the window (written to the keyframe).
  void removeKeyframeStates(int idx, bool fixed);
  //! (host, target) pairs of a candidate point, indexed by target (the host's entry is unused).
  using CandidatePairs = std::array<FramePairPrecalc, kMaxWindowKeyframes>;
  void setCandidatePairs(int host, CandidatePairs &pairs) const;
  void evaluateCandidate(int host, const CandidatePairs &pairs, const PointObservation &obs, double &energy, double &H,
                         double &b, int &inliers) const;

  vpHSlamParameters::Mapper m_mapper;
  PhotometricSettings m_settings;
  double m_gradientWeightC;
  double m_affinePriorA, m_affinePriorB;
  double m_affinePriorAFree, m_affinePriorBFree, m_affinePriorACalib, m_affinePriorBCalib;
  bool m_anchors = true;           //!< globalMap.anchors
  double m_anchorPixelWeight = 0.; //!< globalMap.anchorPixelWeight
  double m_anchorHuberPx = 2.;     //!< globalMap.anchorHuberPx
  int m_anchorMinForScale = 10;    //!< globalMap.anchorMinForScale
  int m_anchoredPoints = 0;        //!< window points with an active anchor (at the last sync)

  std::vector<WindowFrame> m_frames;
  std::vector<KeyframeState> m_states; //!< current states, window order (mirrors Frame::cMw / affine)
  std::vector<WindowPoint> m_points;
  std::vector<int> m_allPoints; //!< 0..m_points.size()-1, the order of full passes
  std::vector<Vec8d, Eigen::aligned_allocator<Vec8d>> m_hxp;
  MarginalizationPrior m_prior;
  int m_gaugeKeyframeId = -1;  //!< id of the keyframe holding the gauge (first added)
  KeyframeState m_gaugeAnchor; //!< its state (kept after it leaves: centre of the scale direction)
  bool m_hasAnchor = false;

  WindowContext m_ctx;
  WindowAccumulator m_acc;
  bool m_accCurrent = false;          //!< m_acc is the linearisation at the current states of the current window
  std::unique_ptr<WorkerPool> m_pool; //!< system.workerThreads threads (+ the caller)
  std::vector<WindowAccumulator> m_workerAcc; //!< one per pool participant, merged in participant order
  std::vector<double> m_workerEnergy;         //!< energyAll(): one partial sum per participant
  Eigen::MatrixXd m_H, m_Hred;
  Eigen::VectorXd m_b, m_bred;
  Eigen::LDLT<Eigen::MatrixXd> m_ldlt;
};
} // namespace hslam

#endif
