/*
 * H-SLAM for ViSP.
 */
/*!
  \file WindowLinearization.h
  \brief Per-point accumulation of the window's normal equations: the hot loop of the photometric BA.

  Layout (the reason this file exists): the window optimiser keeps its points in one flat vector and every point's
  cross blocks H_x,rho (one Vec8d per window keyframe) in one flat preallocated buffer, so a pass over a range of
  points touches only that range's memory plus a per-thread accumulator. Each pass works on a list of point
  indices and a [begin, end) range in it: splitting the list over worker threads only needs one accumulator per
  worker and a final sum (WindowAccumulator::add).

  Two passes per linearisation (DSO's AccumulatedTopHessian / AccumulatedSCHessian split):
  - linearizeRange(): evaluates every residual of the points, sums the RELATIVE-coordinate blocks of each
    (host, target) pair (8x8 + 8, converted once per pair to absolute coordinates by the optimiser), and stores the
    point's own blocks (H_rho,rho, b_rho, absolute H_x,rho per keyframe);
  - schurRange(): from those stored blocks, the Schur complement H_x,rho H_rho,rho^-1 H_rho,x for a damping lambda.
    A rejected LM step only re-runs this cheap pass, not the image look-ups.

  Threading: the functions write only the points of their range (disjoint between workers) and their own
  accumulator; the context is read-only.
*/
#ifndef HSLAM_MAPPING_WINDOW_LINEARIZATION_H
#define HSLAM_MAPPING_WINDOW_LINEARIZATION_H

#include "mapping/AnchorResidual.h"
#include "mapping/PhotometricResidual.h"

#include <Eigen/Core>
#include <Eigen/StdVector>

#include <vector>

namespace hslam
{
//! Upper bound on keyframes in the window (vpHSlamParameters::Mapper::windowSize + 1 must not exceed it).
constexpr int kMaxWindowKeyframes = 16;

//! One point-in-target residual kept between optimisations.
struct WindowResidual {
  int target = -1;                             //!< window index of the target keyframe
  ResidualState state = ResidualState::inlier; //!< at the last evaluation
  double energy = 0.;                          //!< clamped robust energy at the last evaluation
};

//! An active point as the window optimiser sees it.
struct WindowPoint {
  int host = -1;            //!< window index of the host keyframe
  int pointIndex = -1;      //!< index in the host's Keyframe::points
  PointObservation obs;     //!< host pixel, current inverse depth, pointers to the patch (refreshed each optimize())
  double idepthBackup = 0.; //!< state before the last LM step
  double Hpp = 0.;          //!< undamped inverse-depth Hessian at the last linearisation
  double bp = 0.;           //!< inverse-depth gradient at the last linearisation
  int inlierResiduals = 0;
  int outlierResidualsRemoved = 0; //!< residuals removed as outliers so far (outlier-point decision)
  std::vector<WindowResidual> residuals;
  PointAnchor anchor; //!< a re-used global point's tie to its stored keyframe (AnchorResidual.h), else inactive
};

//! Read-only inputs of a pass.
struct WindowContext {
  PhotometricSettings settings;
  int numFrames = 0;
  const PyramidLevel *levels[kMaxWindowKeyframes] = {}; //!< level 0 of each window keyframe
  SE3d poses[kMaxWindowKeyframes];                      //!< world-to-camera pose of each window keyframe (anchors)
  //! pair precalc, host-major: pairs[h * kMaxWindowKeyframes + t]
  std::vector<FramePairPrecalc, Eigen::aligned_allocator<FramePairPrecalc>> pairs;
  WindowContext() : pairs(static_cast<size_t>(kMaxWindowKeyframes * kMaxWindowKeyframes)) {}
  const FramePairPrecalc &pair(int h, int t) const { return pairs[static_cast<size_t>(h * kMaxWindowKeyframes + t)]; }
  FramePairPrecalc &pair(int h, int t) { return pairs[static_cast<size_t>(h * kMaxWindowKeyframes + t)]; }
};

//! Sums of a pass (one per worker).
struct VISP_EXPORT WindowAccumulator {
  int numFrames = 0;
  std::vector<Mat8d, Eigen::aligned_allocator<Mat8d>> pairH; //!< relative coordinates, [h * kMax + t]
  std::vector<Vec8d, Eigen::aligned_allocator<Vec8d>> pairB;
  //! Blocks on one keyframe's own states (anchors: absolute coordinates), [frame]
  std::vector<Mat8d, Eigen::aligned_allocator<Mat8d>> frameH;
  std::vector<Vec8d, Eigen::aligned_allocator<Vec8d>> frameB;
  Eigen::MatrixXd Hsc; //!< Schur term H_x,rho H_rho,rho^-1 H_rho,x (absolute, 8n x 8n)
  Eigen::VectorXd bsc; //!< H_x,rho H_rho,rho^-1 b_rho
  double energy = 0.;
  int inliers = 0;
  int outliers = 0;
  int outOfBounds = 0;

  //! Size for n keyframes (allocates once; later calls with the same n only zero).
  void reset(int n);
  //! Add another worker's sums.
  void add(const WindowAccumulator &other);
};

/*!
  Evaluate and linearise the residuals of points order[begin..end): updates each point's residual states, Hpp, bp
  and its cross blocks hxp[point * kMaxWindowKeyframes + frame], and sums the pair blocks into \e acc.
*/
VISP_EXPORT void linearizeRange(const WindowContext &ctx, std::vector<WindowPoint> &points,
                                const std::vector<int> &order, size_t begin, size_t end, Vec8d *hxp,
                                WindowAccumulator &acc);

//! Schur complement of points order[begin..end) with the damping (1 + lambda) on H_rho,rho, into acc.Hsc/bsc.
VISP_EXPORT void schurRange(const WindowContext &ctx, const std::vector<WindowPoint> &points,
                            const std::vector<int> &order, size_t begin, size_t end, const Vec8d *hxp, double lambda,
                            WindowAccumulator &acc);

//! Energy of points order[begin..end) at their current inverse depth (no Jacobians); counts inliers/outliers.
VISP_EXPORT double energyRange(const WindowContext &ctx, const std::vector<WindowPoint> &points,
                               const std::vector<int> &order, size_t begin, size_t end, int *inliers = nullptr);
} // namespace hslam

#endif
