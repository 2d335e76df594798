/*
 * H-SLAM for ViSP.
 */
/*!
  \file CoarseTracker.h
  \brief Coarse-to-fine direct image alignment of a new frame against the newest keyframe (DSO's coarse tracker).

  What it is for: the direct pose estimate of every new frame. The reference is the newest keyframe with a sparse
  set of points (inverse depths, from any keyframe of the window, already expressed in the reference camera, see
  projectIntoReference()). setReference() turns them into a sparse inverse-depth map per pyramid level (DSO
  makeCoarseDepthL0: weighted average into level-0 pixels, 2x2 sums to coarser levels, one dilation step), and
  every pixel of those maps becomes a single-pixel residual (no patch, as in DSO's coarse tracker):
      r = I_new[pi(newMref * pi^-1(x, y, idepth))] - (a_ji I_ref[x, y] + b_ji)
  with (a_ji, b_ji) the brightness transfer of AffineBrightness (reference affine and exposures fixed, the new
  frame's affine (a, b) estimated). track() runs Levenberg-damped Gauss-Newton over the left-perturbed SE(3)
  (newMref <- exp(delta) newMref, twist (translation, rotation)) and (a, b), coarsest level first, with Huber
  weights and a saturated energy above a cutoff (doubled while more than 60 % of the residuals are cut, DSO).
  trackWithHypotheses() runs DSO's sequence of motion hypotheses (constant velocity, double, half, zero motion,
  small rotations around the constant-velocity guess) and keeps the best.

  Affine priors (own reading of DSO's frame prior): the prior energy wA (a / 10)^2 + wB (b / 1000)^2 on the new
  frame's absolute (a, b) (towards 0, in DSO's scaled units SCALE_A = 10, SCALE_B = 1000) is added to the sum of
  residual energies; wA, wB are Tracker::affinePriorA/B, or the *Calibrated ones when the frames are
  photometrically calibrated (then 1e12 effectively fixes a).

  Threading and ownership: not thread-safe; one tracker per tracking thread. setReference() copies everything it
  needs (reference intensities, intrinsics, affine, exposure), so the reference Frame may be released or changed
  afterwards. All buffers are sized in setReference(); track() does not allocate. The per-point work is split in
  range functions (computeResiduals / accumulate) so a worker pool can share a level later.
*/
#ifndef HSLAM_TRACKING_COARSE_TRACKER_H
#define HSLAM_TRACKING_COARSE_TRACKER_H

#include "features/BinaryDescriptor.h"
#include "map/Frame.h"
#include "tracking/NormalEquations8.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <array>
#include <limits>
#include <vector>

namespace hslam
{
//! Largest number of pyramid levels the tracker handles (per-level results are fixed-size arrays).
constexpr int kCoarseTrackerMaxLevels = 8;

//! RMSE (intensity units) per pyramid level, finest first; NaN for a level not reached.
using CoarseRmsePerLevel = std::array<double, kCoarseTrackerMaxLevels>;

//! A point of the tracking reference, expressed in the reference keyframe.
struct CoarseTrackerPoint {
  float u = 0.f;      //!< level-0 pixel in the reference keyframe, pixels
  float v = 0.f;      //!< level-0 pixel in the reference keyframe, pixels
  float idepth = 0.f; //!< inverse depth in the reference camera, > 0
  float weight = 1.f; //!< > 0, weight of the inverse-depth average (DSO: sqrt(1e-3 * H_idepth), i.e. ~ 1/sigma)
};

/*!
  Express a point hosted by another keyframe in the reference keyframe (DSO uses the point's residual towards the
  reference, "centerProjectedTo"). Returns false when it lands behind the camera or outside the image.
  \param refMhost : host-to-reference transform.
  \param K0 : level-0 intrinsics (shared by host and reference).
*/
VISP_EXPORT bool projectIntoReference(const SE3d &refMhost, const PinholeIntrinsics &K0, int width, int height,
                                      float uHost, float vHost, float idepthHost, float weight,
                                      CoarseTrackerPoint &out);

/*!
  A map point with an ORB descriptor, expressed in the reference keyframe: what the indirect step of hybrid
  tracking projects into a new frame and matches (descriptor sharing: the same points as the direct side's).
*/
struct ReferenceFeature {
  Eigen::Vector3d Xref = Eigen::Vector3d::Zero(); //!< position in the reference camera frame
  OrbDescriptor orb;                              //!< descriptor computed in the host keyframe
  float angleDeg = 0.f;                           //!< its orientation, degrees
  double idepthVar = 0.;                          //!< variance of its inverse depth in the host (0: unknown)
};

/*!
  The geometric half of the joint pose optimisation (paper eq. 1-4): ORB matches kept as inliers by the indirect
  step, each a point in the reference frame and the level-0 pixel it matched in the new frame. track() then
  minimises, per pyramid level (l counted from the coarsest level used, see geometricWeight()),
      E_p / (n_p s_p^2) + K_l E_g / (n_g s_g^2),   K_l = geometricWeight(l, inliers)
  with E_p the photometric energy (mean taken as today), s_p^2 the mean photometric energy per residual at the
  start of the level (estimated from this frame's residuals), E_g the Huber-robust sum of squared reprojection
  errors (threshold sqrt(5.991) pixels) and s_g^2 = \e sigma2Px, the mean squared inlier reprojection error of the
  indirect step (estimated by the caller from this frame's matches).
*/
struct GeometricTerm {
  std::vector<Eigen::Vector3d> Xref; //!< matched points, reference frame
  std::vector<Eigen::Vector2d> uv;   //!< their level-0 pixels in the new frame
  double sigma2Px = 1.;              //!< s_g^2, pixels^2 (> 0)
  int inliers = 0;                   //!< N_g of eq. 4 (the indirect step's inliers)
  /*!
    Paper eq. 3 (tracking.geometricDepthWeights): each match's weight (1 / var_i) / max_j (1 / var_j) over the
    inverse-depth variances of the matched points, so that points of uncertain depth pull the pose less; empty: every
    weight 1. With weights, E_g sums the weighted residuals, \e count is their sum and \e sigma2Px their weighted mean
    squared error (the term keeps the balance eq. 1 gives it, whatever the spread of the weights).
  */
  std::vector<double> weights;
  double count = 0.; //!< n_g of eq. 1 with weights: their sum (0: the number of matches)
  /*!
    Indirect ablation: the pose comes from the geometric term alone (the photometric term only estimates (a, b)),
    and the photometric acceptance checks (outlier share, bound of the previous frame) are not applied.
  */
  bool poseFromGeometryOnly = false;
};

//! Why a track() failed.
enum class CoarseTrackingStatus {
  ok,                    //!< converged and passed every check
  noReference,           //!< setReference() was not called or gave no usable point
  tooFewResiduals,       //!< fewer residuals than kCoarseMinResiduals land in the new image at some level
  worseThanBound,        //!< a level's RMSE exceeds 1.5x the bound given (DSO: worse than a previous hypothesis)
  tooManyOutliers,       //!< at level 0, more than 60 % of the residuals exceed the base cutoff
  implausibleBrightness, //!< |log a_ji| > 1.5 or |b_ji| > 200 relative to the reference (DSO)
  notFinite              //!< the energy or the estimate became NaN / inf
};

//! Short English description of a status, for logs.
VISP_EXPORT const char *coarseTrackingStatusName(CoarseTrackingStatus status);

//! Everything track() measured; filled on success and on failure.
struct CoarseTrackingResult {
  bool success = false;
  CoarseTrackingStatus status = CoarseTrackingStatus::noReference;
  int failedLevel = -1;        //!< level where a check failed, -1 when none
  SE3d newMref;                //!< final estimate (reference-to-new), also on failure
  AffineBrightness affine;     //!< final (a, b) of the new frame
  CoarseRmsePerLevel rmse;     //!< DSO lastResiduals: sqrt(mean energy) per level, intensity units
  int numLevels = 0;           //!< levels used
  double flowT = 0.;           //!< mean squared pixel shift from the translation only, px^2 (DSO)
  double flowR = 0.;           //!< mean squared pixel shift from the rotation only, px^2 (DSO leaves it 0)
  double flowRT = 0.;          //!< mean squared pixel shift from rotation and translation, px^2 (DSO)
  double inlierRatio = 0.;     //!< level 0: share of residuals below the base cutoff
  int residuals = 0;           //!< level 0: residuals in the energy (inside the new image)
  int iterations = 0;          //!< Gauss-Newton iterations over all levels
  int hypothesesTried = 0;     //!< trackWithHypotheses(): hypotheses run; track(): 1
  double geometricWeight = 0.; //!< K of eq. 4 at the finest level (0 without a geometric term)
  CoarseTrackingResult() { rmse.fill(std::numeric_limits<double>::quiet_NaN()); }
};

//! The motion of the last two frames relative to the current reference, for trackWithHypotheses().
struct CoarseMotionHistory {
  bool valid = false;           //!< false: only "no motion from the reference" is tried (DSO: first frames)
  SE3d lastMref;                //!< reference-to-last-frame transform
  SE3d prelastMref;             //!< reference-to-frame-before-last transform
  AffineBrightness lastAffine;  //!< (a, b) of the last frame: the start value of every hypothesis
  bool hasIndirectPose = false; //!< the indirect step gave a pose: tried after constant velocity (first if !valid)
  SE3d indirectMref;            //!< that pose (reference-to-new)
};

/*!
  Direct coarse-to-fine tracker. See the file comment.
  \code
  CoarseTracker tracker(params.tracker);
  tracker.setReference(*newestKf->frame, points);
  CoarseTrackingResult result;
  SE3d newMref; AffineBrightness affine;
  if (tracker.trackWithHypotheses(*frame, history, newMref, affine, result)) { ... }
  \endcode
*/
class VISP_EXPORT CoarseTracker
{
public:
  /*!
    \param params : thresholds (copied).
    \param photometricCalibration : frames are photometrically calibrated (selects the calibrated affine priors).
    \exception vpHSlamException::invalidArgument when iterationsPerLevel is empty or a threshold is not positive.
  */
  explicit CoarseTracker(const vpHSlamParameters::Tracker &params, bool photometricCalibration = false);

  //! Select the calibrated (true) or the uncalibrated affine priors.
  void setPhotometricCalibration(bool calibrated) { m_photometricCalibration = calibrated; }

  /*!
    Make \e refKf the reference with \e points (expressed in it). Builds the per-level inverse-depth maps and
    point lists and sizes every buffer. Resets firstRmse().
    \exception vpHSlamException::invalidArgument when the pyramid is empty or has more than kCoarseTrackerMaxLevels.
  */
  void setReference(const Frame &refKf, const std::vector<CoarseTrackerPoint> &points);

  /*!
    Align \e newFrame to the reference starting from (newMref, affine). On success both are overwritten with the
    estimate; on failure they are left untouched (the estimate is in result.newMref / result.affine).
    \param abortRmse : optional per-level bound: the run fails as soon as a level's RMSE exceeds 1.5x it (DSO).
    \exception vpHSlamException::invalidImage when the frame's size or level count differs from the reference.
  */
  bool track(const Frame &newFrame, SE3d &newMref, AffineBrightness &affine, CoarseTrackingResult &result,
             const CoarseRmsePerLevel *abortRmse = nullptr);

  /*!
    DSO trackNewCoarse: the hypotheses of makeMotionHypotheses() in order, each bounded by the best RMSE achieved so
    far; stops once the level-0 RMSE is below retrackResidualFactor x the last frame's. Keeps the best. On failure
    of all, newMref / affine are set to the first hypothesis and history.lastAffine and false is returned.
  */
  bool trackWithHypotheses(const Frame &newFrame, const CoarseMotionHistory &history, SE3d &newMref,
                           AffineBrightness &affine, CoarseTrackingResult &result);

  /*!
    Initial guesses of newMref, in DSO's order: constant velocity, double motion, half motion, zero motion from the
    last frame, zero motion from the reference, then the constant-velocity guess right-multiplied by a rotation of
    quaternion (1, d x, d y, d z) for each of the 26 directions (x, y, z) in {-1, 0, 1}^3 \ {0}, first with DSO's
    d = 0.02 (~2.3 degrees about an axis), then d = 0.04 (our addition): 57 hypotheses. With an invalid history:
    only the identity.
  */
  static void makeMotionHypotheses(const CoarseMotionHistory &history, std::vector<SE3d> &hypotheses);
  //! The first of those hypotheses: the last motion repeated (identity with an invalid history).
  static SE3d predictConstantVelocity(const CoarseMotionHistory &history);

  /*!
    Lowers the per-level bound \e achieved of trackWithHypotheses() to \e attempt's RMSE where that is lower. Every
    level an attempt completed counts (DSO), except the level at which a failed attempt failed: that RMSE is no fit.
    A hypothesis whose brightness collapses (gain towards 0 flattens the image and its residuals) fails the
    brightness check at the coarsest level with an RMSE far below any true fit's; taken as the bound, it failed
    every later hypothesis, the right one included (a hand-held turn about an axis 20 cm behind the camera, frame
    315: 1.53 against 6.07 at the coarsest level, and the frame kept a pose 5 cm off).
  */
  static void lowerHypothesisBound(CoarseRmsePerLevel &achieved, const CoarseTrackingResult &attempt);

  //! Points with descriptors of the reference (set by the mapper with setReference(); empty in direct mode).
  void setReferenceFeatures(std::vector<ReferenceFeature> features) { m_features = std::move(features); }
  const std::vector<ReferenceFeature> &referenceFeatures() const { return m_features; }
  /*!
    Geometric term of the next track() / trackWithHypotheses() calls (see GeometricTerm); nullptr (default) for
    pure direct alignment, exactly DSO's. The object must outlive those calls.
  */
  void setGeometricTerm(const GeometricTerm *term) { m_geometric = term; }
  /*!
    Geometric energy (Huber-robust, see GeometricTerm) of \e newMref and, when H / b are given, its Gauss-Newton
    terms for the left-perturbed twist (translation, rotation), added to the top-left 6x6 block / 6 rows.
    Exposed for the Jacobian test.
  */
  static double geometricEnergy(const GeometricTerm &term, const PinholeIntrinsics &K0, const SE3d &newMref,
                                Eigen::Matrix<double, 8, 8> *H = nullptr, Eigen::Matrix<double, 8, 1> *b = nullptr);
  //! Level-0 RMSE of the first frame tracked against this reference (DSO firstCoarseRMSE), NaN before.
  double firstRmse() const { return m_firstRmse; }
  /*!
    What the next frame's hypotheses are measured against: per level, the last successful frame's RMSE (DSO), or the
    one before when the last beat it by more than retrackResidualFactor. A repeated image (a camera delivering a
    buffer twice, 24 fps video shown at 30) aligns to the keyframe made from its twin with an RMSE near 0; against
    it, the next real frame was never "good enough", so all 57 hypotheses ran (7-Scenes with every 4th image
    repeated: tracking p95 32 ms instead of 3.4 ms), and had the first failed, the others' bound (5x it) would have
    failed them all. Taking the larger of the two always also stopped hypotheses that help: KITTI 06 fed every 3rd
    frame went from 0.082 to 0.295 m.
  */
  CoarseRmsePerLevel recentRmse() const;
  //! Carry DSO's lastCoarseRMSE (and the one before) over to another tracker (one prepared for the next reference).
  void carryRecentRmseFrom(const CoarseTracker &other)
  {
    m_lastRmse = other.m_lastRmse;
    m_prelastRmse = other.m_prelastRmse;
  }
  /*!
    Mean level-0 pixel distance between where the reference's points land at \e fromMref and at \e toMref (an even
    sample of at most kShiftSamplePoints of them; points behind either camera are left out); NaN without a reference
    or when no point is in front of both. Adaptive tracking measures the predicted motion with it: the last frame's
    pose against the constant-velocity prediction.
  */
  double meanShiftPx(const SE3d &fromMref, const SE3d &toMref) const;
  //! Points meanShiftPx() projects at most.
  static constexpr int kShiftSamplePoints = 256;
  //! What trackWithHypotheses() remembers from frame to frame (the bounds of the next frame's hypotheses).
  struct RetrackState {
    CoarseRmsePerLevel lastRmse, prelastRmse;
    double firstRmse = 0.;
  };
  //! That memory, to undo an alignment whose result is not kept (adaptive tracking runs two on a doubtful frame).
  RetrackState retrackState() const { return {m_lastRmse, m_prelastRmse, m_firstRmse}; }
  void restoreRetrackState(const RetrackState &state)
  {
    m_lastRmse = state.lastRmse;
    m_prelastRmse = state.prelastRmse;
    m_firstRmse = state.firstRmse;
  }
  //! Levels of the reference, 0 before setReference().
  int numLevels() const { return m_numLevels; }
  //! Residual points (pixels of the inverse-depth map) of a level.
  int numPoints(int level) const { return m_levels[static_cast<size_t>(level)].numPoints; }

  //! Per-range statistics of computeResiduals(); ranges combine by operator+=.
  struct ResidualStats {
    double energy = 0.;         //!< sum of Huber energies (saturated ones at the cutoff energy)
    int numTerms = 0;           //!< residuals inside the new image
    int numSaturated = 0;       //!< residuals above the current cutoff
    int numAboveBaseCutoff = 0; //!< residuals above the base cutoff (for the inlier ratio)
    double shiftT = 0., shiftR = 0., shiftRT = 0.;
    int shiftSamples = 0;
    ResidualStats &operator+=(const ResidualStats &o);
  };

  /*!
    Warp points [begin, end) of \e level with the current warp (set by track()) and fill the per-point buffers
    read by accumulate(). Exposed so a worker pool can split a level; track() calls it on the whole range.
  */
  void computeResiduals(int level, int begin, int end, float cutoff, ResidualStats &stats);
  //! Add the Gauss-Newton terms of points [begin, end) (after computeResiduals()) to \e eq.
  void accumulate(int begin, int end, NormalEquations8 &eq) const;

private:
  struct LevelData {
    int width = 0, height = 0;
    PinholeIntrinsics K;
    std::vector<float> idepthMap, weightMap, weightBackup; //!< per pixel
    std::vector<float> pu, pv, pidepth, pcolor;            //!< per residual point (SoA)
    int numPoints = 0;
  };
  //! The warp of the current iteration, shared by computeResiduals() over ranges.
  struct Warp {
    Eigen::Matrix3f RKinv;
    Eigen::Vector3f t;
    Eigen::Matrix3f Kinv;
    float aji = 1.f, bji = 0.f, refB = 0.f;
    float fx = 0.f, fy = 0.f, cx = 0.f, cy = 0.f;
    float baseCutoff = 0.f;
    const PyramidLevel *target = nullptr;
  };

  void buildDepthMaps(const std::vector<CoarseTrackerPoint> &points);
  //! One dilation of empty pixel \e i from its filled neighbours at \e offsets (buildDepthMaps).
  static void dilatePixel(LevelData &L, int i, const int (&offsets)[4]);
  void setWarp(int level, const PyramidLevel &target, const SE3d &newMref, const AffineBrightness &affine,
               double newExposure);
  ResidualStats evaluate(int level, const PyramidLevel &target, const SE3d &newMref, const AffineBrightness &affine,
                         double newExposure, float cutoff);
  void buildSystem(int level, const ResidualStats &stats, const AffineBrightness &affine,
                   Eigen::Matrix<double, 8, 8> &H, Eigen::Matrix<double, 8, 1> &b) const;
  double priorEnergy(const AffineBrightness &affine) const;
  //! Weights of the photometric and geometric parts of a level's objective (joint objective, GeometricTerm).
  struct LevelWeights {
    bool joint = false; //!< a geometric term is set: the weights apply
    double wp = 1.;     //!< 1 / s_p^2
    double wg = 0.;     //!< K_l / (n_g s_g^2)
    double K = 0.;      //!< K_l (eq. 4)
  };
  //! evaluate(), the cutoff doubled while too many residuals saturate (DSO); \e cutoffRepeat the factor used.
  ResidualStats evaluateWithCutoffRepeat(int level, const PyramidLevel &target, const SE3d &newMref,
                                         const AffineBrightness &affine, double newExposure, float baseCutoff,
                                         float &cutoffRepeat);
  //! Weights of the level \e stepFromCoarsest steps below the coarsest one, from its first evaluation \e stats.
  LevelWeights levelWeights(int stepFromCoarsest, const ResidualStats &stats) const;
  //! The objective a level minimises: mean photometric energy with the priors, plus the weighted geometric term.
  double levelObjective(const LevelWeights &weights, const ResidualStats &stats, const AffineBrightness &affine,
                        const SE3d &newMref) const;
  //! Normal equations of levelObjective() at the last evaluated state.
  void levelSystem(int level, const LevelWeights &weights, const ResidualStats &stats, const AffineBrightness &affine,
                   const SE3d &newMref, Eigen::Matrix<double, 8, 8> &H, Eigen::Matrix<double, 8, 1> &b) const;
  //! Levenberg-damped Gauss-Newton on one level (DSO trackNewestCoarse's inner loop); \e stats of the kept state.
  void optimizeLevel(int level, const PyramidLevel &target, double newExposure, float cutoff,
                     const LevelWeights &weights, SE3d &newMref, AffineBrightness &affine, ResidualStats &stats,
                     int &iterations);
  //! The brightness transfer from the reference is plausible (DSO: |log a_ji| <= 1.5, |b_ji| <= 200).
  bool brightnessPlausible(double newExposure, const AffineBrightness &affine) const;

  vpHSlamParameters::Tracker m_params;
  bool m_photometricCalibration;
  int m_numLevels = 0;
  std::array<LevelData, kCoarseTrackerMaxLevels> m_levels;
  AffineBrightness m_refAffine;
  double m_refExposure = 1.;
  Warp m_warp;
  // Per-point buffers of the level being optimised (indexed by point; weight 0 = not a residual).
  std::vector<float> m_bufIdepth, m_bufU, m_bufV, m_bufDx, m_bufDy, m_bufResidual, m_bufWeight, m_bufRefColor;
  double m_firstRmse;
  CoarseRmsePerLevel m_lastRmse;    //!< best RMSE per level of the last successful frame (DSO lastCoarseRMSE)
  CoarseRmsePerLevel m_prelastRmse; //!< the successful frame's before m_lastRmse
  std::vector<SE3d> m_hypotheses;   //!< reused by trackWithHypotheses()
  std::vector<ReferenceFeature> m_features;
  const GeometricTerm *m_geometric = nullptr;
  PinholeIntrinsics m_K0; //!< level-0 intrinsics of the reference (geometric term)
};
} // namespace hslam

#endif
