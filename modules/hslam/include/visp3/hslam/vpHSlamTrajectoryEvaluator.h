/*
 * H-SLAM for ViSP.
 */
/*!
  \file vpHSlamTrajectoryEvaluator.h
  \brief Accuracy of an estimated trajectory against ground truth: ATE, RPE and the TUM monoVO alignment error.
*/
#ifndef VP_HSLAM_TRAJECTORY_EVALUATOR_H
#define VP_HSLAM_TRAJECTORY_EVALUATOR_H

#include <visp3/core/vpConfig.h>
#include <visp3/core/vpHomogeneousMatrix.h>
#include <visp3/core/vpImage.h>
#include <visp3/core/vpRGBa.h>
#include <visp3/hslam/vpHSlamTrajectory.h>

#include <string>
#include <utility>
#include <vector>

/*!
  \class vpHSlamTrajectoryEvaluator
  \ingroup group_hslam
  \brief Compares an estimated trajectory with a ground truth, the way the TUM RGB-D, TUM monoVO and KITTI
  benchmarks do.

  What it is for: the numbers a SLAM paper reports. At construction every estimate timestamp is associated with
  the nearest ground-truth timestamp within a maximum time difference (default 0.02 s, one-to-one, as the TUM
  benchmark's associate.py). Then:
  - computeAte(): absolute trajectory error on positions after a closed-form Umeyama alignment of the estimate
    onto the ground truth, in SE(3), Sim(3) (monocular: scale unobservable) or none. RMSE, mean, median, max, min,
    std of the per-pair distance, in ground-truth units (metres).
  - computeRpe(): relative pose error over a time delta (seconds) or a travelled-distance delta (metres of ground
    truth): translation (metres) and rotation (degrees) errors of relative motions.
  - computeAlignmentError(): the TUM monoVO e_align (Engel et al. 2016): start and end segments aligned
    separately with Sim(3), RMS distance between the two alignments of every estimated position, plus drifts.
  - drawTopView(): a top-view picture of ground truth and aligned estimate.

  Threading and ownership: copies both trajectories at construction; const methods may be called from several
  threads. Errors (no association, too few pairs, bad options) are thrown as vpHSlamException.

  \code
  vpHSlamTrajectory gt = vpHSlamTrajectory::readTum("groundtruth.txt");
  vpHSlamTrajectory est = vpHSlamTrajectory::readTum("estimate.txt");
  vpHSlamTrajectoryEvaluator evaluator(gt, est, 0.02);
  vpHSlamTrajectoryEvaluator::AteResult ate = evaluator.computeAte(vpHSlamTrajectoryEvaluator::alignSim3);
  std::cout << "ATE RMSE " << ate.error.rmse << " m over " << ate.error.count << " poses, scale " << ate.scale;
  \endcode
*/
class VISP_EXPORT vpHSlamTrajectoryEvaluator
{
public:
  //! Transformation family aligning the estimate onto the ground truth.
  enum Alignment {
    alignNone, //!< no alignment (estimate already in the ground-truth frame)
    alignSE3,  //!< rotation + translation
    alignSim3  //!< rotation + translation + scale
  };

  //! Summary of a list of non-negative errors.
  struct Statistics {
    size_t count = 0;   //!< number of errors
    double rmse = 0.;   //!< root mean square
    double mean = 0.;   //!< arithmetic mean
    double median = 0.; //!< median (mean of the two middle values for an even count)
    double max = 0.;    //!< largest error
    double min = 0.;    //!< smallest error
    double std = 0.;    //!< population standard deviation
  };

  //! Absolute trajectory error.
  struct AteResult {
    Alignment alignment = alignSim3; //!< alignment used
    Statistics error;                //!< position errors after alignment, ground-truth units
    double scale = 1.;               //!< Sim(3) scale (1 for SE(3) and none)
    vpHomogeneousMatrix gMe;         //!< rotation and translation of the alignment: p_gt = scale gRe p_est + gte
  };

  //! Relative pose error.
  struct RpeResult {
    double delta = 0.;       //!< seconds (time) or metres (distance)
    bool byDistance = false; //!< delta measured along the ground-truth path instead of time
    double scale = 1.;       //!< scale applied to estimated translations (from the alignment)
    Statistics translation;  //!< metres
    Statistics rotationDeg;  //!< degrees
  };

  //! TUM monoVO alignment error (Engel et al. 2016).
  struct AlignmentErrorResult {
    double segmentLength = 0.;    //!< seconds of associated poses in each of the start and end segments
    double alignmentError = 0.;   //!< e_align, ground-truth units
    double translationDrift = 0.; //!< translation norm of T_s T_e^-1
    double rotationDriftDeg = 0.; //!< rotation angle of T_s T_e^-1, degrees
    double scaleDrift = 1.;       //!< s_start / s_end
    size_t startCount = 0;        //!< associated poses in the start segment
    size_t endCount = 0;          //!< associated poses in the end segment
  };

  /*!
    Associate both trajectories.
    \param groundTruth : reference poses wMc.
    \param estimate : estimated poses wMc (any world frame and, for Sim(3), any scale).
    \param maxTimeDifference : largest |t_est - t_gt| of an associated pair, seconds (> 0 or == 0 for exact).
  */
  vpHSlamTrajectoryEvaluator(const vpHSlamTrajectory &groundTruth, const vpHSlamTrajectory &estimate,
                             double maxTimeDifference = 0.02);

  //! Number of associated (estimate, ground truth) pairs.
  size_t getMatchedCount() const { return m_matches.size(); }
  //! Associated pairs (estimate index, ground-truth index), sorted by estimate time.
  const std::vector<std::pair<size_t, size_t>> &getMatches() const { return m_matches; }

  //! ATE after \e alignment. \throw vpHSlamException when fewer than 3 pairs (1 for alignNone) are associated.
  AteResult computeAte(Alignment alignment = alignSim3) const;
  /*!
    RPE over \e delta seconds (or metres of ground-truth path when \e byDistance). Estimated translations are
    scaled by the Sim(3) scale when \e alignment is alignSim3 (rigid alignments do not change relative poses).
  */
  RpeResult computeRpe(double delta, bool byDistance = false, Alignment alignment = alignSim3) const;
  /*!
    TUM monoVO alignment error with start/end segments of \e segmentLength seconds of associated poses.
    The monoVO benchmark's ground truth covers 10-20 s at each end, hence the default of 10 s.
  */
  AlignmentErrorResult computeAlignmentError(double segmentLength = 10.) const;

  //! The whole estimate (all poses, associated or not) mapped into the ground-truth frame by \e ate's alignment.
  vpHSlamTrajectory getAlignedEstimate(const AteResult &ate) const;

  /*!
    Draw a top view: ground truth and estimate projected on the two dominant directions of the ground-truth
    positions (principal axes), a metric grid with its spacing written, a legend and an optional caption line.
    \param I : resized to \e width x \e height.
    \param groundTruth : reference trajectory (green).
    \param estimate : estimate already in the ground-truth frame, e.g. getAlignedEstimate() (red).
    \param caption : optional line written at the bottom.
    \param width, height : picture size, pixels.
  */
  static void drawTopView(vpImage<vpRGBa> &I, const vpHSlamTrajectory &groundTruth, const vpHSlamTrajectory &estimate,
                          const std::string &caption = "", unsigned int width = 900, unsigned int height = 900);

  //! Parse "none", "se3" or "sim3". \throw vpHSlamException (invalidArgument) otherwise.
  static Alignment alignmentFromString(const std::string &name);
  //! "none", "se3" or "sim3".
  static std::string alignmentToString(Alignment alignment);

private:
  vpHSlamTrajectory m_groundTruth;
  vpHSlamTrajectory m_estimate;
  double m_maxTimeDifference;                       //!< seconds
  std::vector<std::pair<size_t, size_t>> m_matches; //!< (estimate index, ground-truth index)
};

#endif
