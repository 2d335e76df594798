/*
 * H-SLAM for ViSP.
 */
/*!
  \file PhotometricResidual.h
  \brief The photometric residual of one point's 8-pixel pattern in one target keyframe, with analytic Jacobians.

  Residual of pattern pixel k of a point hosted in keyframe h (pixel (u, v) + offset_k, inverse depth rho),
  observed in target keyframe t (DSO, Engel et al. 2018, eq. 4):
      r_k = I_t[pi(T_th pi^-1(u_k, v_k, rho))] - b_th - a_th P_k,
  where P_k is the host intensity stored in the point's patch and (a_th, b_th) the brightness transfer of
  AffineBrightness::transfer(). Every pattern pixel shares the point's inverse depth (DSO: fronto-parallel patch).

  Jacobians are taken in RELATIVE coordinates, 9 columns, (eps (6), alpha, beta, rho):
  - eps: left perturbation of the relative pose, T_th <- exp(eps) T_th (twist order translation, rotation);
  - alpha: a_th <- a_th e^alpha (log-ratio of the gains), beta: b_th <- b_th + beta;
  - rho: the host inverse depth.
  They are exact per pattern pixel (each pixel's own projection), not DSO's centre-pixel approximation: the
  cost is a few flops more per pixel and the derivatives are then checkable against numeric differences.
  relativeToAbsolute() gives the chain rule to the absolute states of host and target (left-perturbed cMw, a, b):
  eps = d_t - Ad(T_th) d_h (DSO's adjoint chain), alpha = a_t - a_h, beta = b_t - a_th b_h (linearised).

  Robust weighting (DSO): energy_k = w_k huber(r_k) with w_k = patchWeight_k (c^2/(c^2+|grad I_h|^2)), Huber
  threshold from the tracker parameters; the IRLS weight of pixel k is w_k * min(1, huber / |r_k|).

  Threading: free functions without state; safe to call concurrently.
*/
#ifndef HSLAM_MAPPING_PHOTOMETRIC_RESIDUAL_H
#define HSLAM_MAPPING_PHOTOMETRIC_RESIDUAL_H

#include "features/ImagePyramid.h"
#include "features/PatchPattern.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>

#include <Eigen/Core>

#include <array>

namespace hslam
{
//! Number of Jacobian columns in relative coordinates: relative pose (6), alpha, beta, inverse depth.
constexpr int kRelativeDims = 9;
//! Pose + affine (a, b) states of one keyframe.
constexpr int kFrameDims = 8;

using Vec8d = Eigen::Matrix<double, kFrameDims, 1>;
using Mat8d = Eigen::Matrix<double, kFrameDims, kFrameDims>;

//! Settings of the residual, taken from vpHSlamParameters::Tracker.
struct PhotometricSettings {
  PinholeIntrinsics K;                        //!< level-0 intrinsics (host and target share the camera)
  double huberThreshold = 9.;                 //!< intensity units (DSO)
  double outlierEnergy = 144. * kPatternSize; //!< summed pattern energy above which the residual is an outlier
};

//! Relative quantities of a (host, target) pair, computed once per pair and iteration.
struct VISP_EXPORT FramePairPrecalc {
  Eigen::Matrix3d R_th = Eigen::Matrix3d::Identity(); //!< rotation of T_th = cTw_t * (cTw_h)^-1
  Eigen::Vector3d t_th = Eigen::Vector3d::Zero();     //!< translation of T_th
  double a_th = 1.;                                   //!< brightness transfer gain host -> target
  double b_th = 0.;                                   //!< brightness transfer offset host -> target
  double bHost = 0.;                                  //!< host offset b_h (chain rule of beta)
  Mat8d dRelative_dHost;                              //!< d(eps, alpha, beta) / d(host pose, a_h, b_h)
  Mat8d dRelative_dTarget;                            //!< d(eps, alpha, beta) / d(target pose, a_t, b_t)

  /*!
    Fill everything from the absolute states (world-to-camera poses, affine (a, b), exposures).
  */
  void set(const SE3d &hostMw, double aHost, double bHost, double exposureHost, const SE3d &targetMw, double aTarget,
           double bTarget, double exposureTarget);
};

//! Host-side description of a point (the patch lives in MapPoint; pointers avoid copying it).
struct PointObservation {
  double u = 0.;                 //!< host pixel, level 0
  double v = 0.;                 //!< host pixel, level 0
  double idepth = 0.;            //!< host inverse depth
  const float *patch = nullptr;  //!< kPatternSize host intensities
  const float *weight = nullptr; //!< kPatternSize gradient weights
  double idepthPrior = 0.;       //!< prior on idepth (a re-used global point), see priorWeight
  double priorWeight = 0.;       //!< 1 / prior variance; 0 = no prior (energy += priorWeight (idepth - prior)^2)
};

//! Outcome of evaluating one point in one target.
enum class ResidualState : unsigned char {
  inlier,      //!< every pattern pixel projects into the image, energy below the outlier threshold
  outOfBounds, //!< behind the camera, non-positive inverse depth or a pattern pixel outside the image
  outlier      //!< summed energy above PhotometricSettings::outlierEnergy
};

//! Per-pixel residuals, robust weights and Jacobians of one pattern (columns: eps (6), alpha, beta, rho).
struct PatternLinearization {
  std::array<double, kPatternSize> r{};      //!< raw residuals, intensity units
  std::array<double, kPatternSize> weight{}; //!< IRLS weights (gradient weight x Huber weight)
  Eigen::Matrix<double, kPatternSize, kRelativeDims> J;
  double energy = 0.; //!< sum of w_k huber(r_k)
};

//! Huber energy of a residual: r^2 inside, k (2|r| - k) outside (DSO's hw r^2 (2 - hw)).
inline double huberEnergy(double r, double k)
{
  const double a = r < 0. ? -r : r;
  return a <= k ? r * r : k * (2. * a - k);
}

/*!
  Evaluate a point's pattern in a target image. With \e lin non-null, also the residuals, weights and Jacobians.
  \return the state; \e energy gets the robust energy (valid for inlier and outlier states).
*/
VISP_EXPORT ResidualState evaluatePattern(const PhotometricSettings &settings, const PyramidLevel &target,
                                          const FramePairPrecalc &pair, const PointObservation &point, double &energy,
                                          PatternLinearization *lin);

/*!
  Sample a point's patch (host intensities) and gradient weights c^2 / (c^2 + |grad|^2) (DSO) from its host level 0.
  \return false when a pattern pixel falls outside the image (the arrays are then left unchanged).
*/
VISP_EXPORT bool samplePatch(const PyramidLevel &host, double u, double v, double gradientWeightC,
                             std::array<float, kPatternSize> &patch, std::array<float, kPatternSize> &weight);

//! Bilinear interpolation needs this many pixels from the right/bottom border, plus one of safety (DSO: margin).
constexpr float kProjectionMargin = 1.f;
} // namespace hslam

#endif
