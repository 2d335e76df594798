/*
 * H-SLAM for ViSP.
 */
/*!
  \file ImmaturePointTracer.h
  \brief Creation of immature points and their epipolar tracing in new frames (DSO's ImmaturePoint::traceOn).

  A candidate point selected in a keyframe has an inverse-depth INTERVAL [idepthMin, idepthMax], infinite at first.
  Every later frame projects the interval onto its epipolar line, searches the line with the 8-pixel pattern
  (Huber SSD, affine brightness transfer applied), refines the best match by Gauss-Newton along the line, and
  turns the refined position +- its expected pixel error back into a new, smaller interval (DSO, Engel et al. 2016,
  sec. 3.2 "Candidate point tracking"; same structure and default thresholds as DSO's ImmaturePoint::traceOn).

  Threading: the tracer is immutable after construction; trace() only writes the point it is given, so points
  may be traced concurrently from several threads. Frames are read only.
*/
#ifndef HSLAM_MAPPING_IMMATURE_POINT_TRACER_H
#define HSLAM_MAPPING_IMMATURE_POINT_TRACER_H

#include "features/ImagePyramid.h"
#include "features/PatchPattern.h"
#include "map/Frame.h"
#include "map/ImmaturePoint.h"
#include "math/SE3.h"

#include <visp3/core/vpConfig.h>
#include <visp3/hslam/vpHSlamParameters.h>

#include <Eigen/Core>

#include <array>
#include <optional>
#include <vector>

namespace hslam
{
/*!
  Everything shared by the points of one host traced in one target (DSO's per frame-pair precalculation):
  level-0 geometry K R K^-1 and K t of targetMhost, the brightness transfer, the pattern rotated into the target
  and the images. Build it with ImmaturePointTracer::makeContext(); it points into the frames, which must outlive
  it.
*/
struct TraceContext {
  EIGEN_MAKE_ALIGNED_OPERATOR_NEW
  Eigen::Matrix3f KRKi = Eigen::Matrix3f::Identity();          //!< K R_th K^-1 (host pixel -> target pixel at infinity)
  Eigen::Vector3f Kt = Eigen::Vector3f::Zero();                //!< K t_th (times idepth: the parallax part)
  float aji = 1.f;                                             //!< brightness transfer: I_target ~ aji I_host + bji
  float bji = 0.f;                                             //!< intensity units
  float maxPixelSearch = 0.f;                                  //!< longest searched segment, pixels
  std::array<Eigen::Vector2f, kPatternSize> rotatedPattern;    //!< pattern offsets as seen in the target, pixels
  Eigen::Vector2f rotatedPatternMin = Eigen::Vector2f::Zero(); //!< bounding box of rotatedPattern: lowest offsets
  Eigen::Vector2f rotatedPatternMax = Eigen::Vector2f::Zero(); //!< ... and highest offsets, pixels
  const PyramidLevel *hostLevel = nullptr;   //!< level 0 of the host (gradient structure of the patch)
  const PyramidLevel *targetLevel = nullptr; //!< level 0 of the target (searched image)
};

//! Details of one trace, for statistics, display and tests.
struct TraceResult {
  TraceStatus status = TraceStatus::uninitialized;
  float u = -1.f;            //!< matched (good) or predicted (skipped, badCondition) target pixel, level 0
  float v = -1.f;            //!< (-1, -1) when out of bounds or outlier
  float pixelInterval = 0.f; //!< length of the new interval on the epipolar line, pixels (DSO lastTracePixelInterval)
  float bestEnergy = 0.f;    //!< pattern energy at the refined match (gradient-weighted Huber)
  int searchSteps = 0;       //!< number of positions visited by the discrete search
};

//! Counts of the statuses returned by a batch of traces.
struct TraceStatistics {
  int total = 0, good = 0, outOfBounds = 0, skipped = 0, badCondition = 0, outlier = 0, uninitialized = 0;
  void add(TraceStatus status);
};

/*!
  Creates immature points in a host frame and traces them in later frames.
  Parameters: the mapper's trace* settings and the tracker's photometric settings (Huber threshold, gradient weight
  constant, per-pixel outlier energy), so tracing scores pixels the way the window optimisation will.

  Usage (mapping thread, for every new frame and every window keyframe):
  \code
  ImmaturePointTracer tracer(params.mapper, params.tracker);
  ImmaturePoint pt;
  if (tracer.createImmaturePoint(*keyframe->frame, u, v, level, pt)) keyframe->immature.push_back(pt);
  TraceStatistics stats = tracer.traceAll(keyframe->immature, *keyframe->frame, *newFrame);
  \endcode
*/
class VISP_EXPORT ImmaturePointTracer
{
public:
  ImmaturePointTracer(const vpHSlamParameters::Mapper &mapper, const vpHSlamParameters::Tracker &tracker);

  /*!
    Fill \e pt for pixel (u, v) (level 0) of \e host: pattern intensities, gradient weights c^2/(c^2+|g|^2),
    energy threshold (DSO: pattern size x per-pixel outlier energy), infinite interval.
    \return false when the pattern does not fit inside the image (then \e pt is unspecified).
  */
  bool createImmaturePoint(const Frame &host, float u, float v, int selectionLevel, ImmaturePoint &pt) const;

  /*!
    Pair precalculation for tracing points of \e host in \e target.
    \param targetMhost : host camera -> target camera.
    \param aji, bji : brightness transfer host -> target (AffineBrightness::transfer()).
    \param K0 : level-0 intrinsics shared by both frames.
  */
  TraceContext makeContext(const Frame &host, const Frame &target, const SE3d &targetMhost, double aji, double bji,
                           const PinholeIntrinsics &K0) const;

  /*!
    Trace one point (DSO traceOn): updates its interval, quality and lastStatus.
    \param result : optional details of this trace.
    \return the new status (also stored in pt.lastStatus).
  */
  TraceStatus trace(ImmaturePoint &pt, const TraceContext &context, TraceResult *result = nullptr) const;

  //! Convenience: makeContext() then trace() for a single point.
  TraceStatus trace(ImmaturePoint &pt, const Frame &host, const Frame &target, const SE3d &targetMhost, double aji,
                    double bji, const PinholeIntrinsics &K0, TraceResult *result = nullptr) const;

  /*!
    Trace every point of \e points (all hosted by \e host) in \e target, using the frames' poses (cMw),
    exposures and affine brightness for the geometry and the brightness transfer (DSO traceNewCoarse).
  */
  TraceStatistics traceAll(std::vector<ImmaturePoint> &points, const Frame &host, const Frame &target) const;

  /*!
    Length in pixels, in the image of a camera at \e targetMhost (level-0 intrinsics \e K0), of the segment onto
    which the point's interval projects; infinite when idepthMax is not finite. Used by activation to judge
    whether an interval is small enough (DSO: lastTracePixelInterval < 8).
  */
  static float projectedIntervalLength(const ImmaturePoint &pt, const SE3d &targetMhost, const PinholeIntrinsics &K0);

private:
  struct TraceEnd;        // how a trace ends: status, reported target pixel and interval length
  struct EpipolarSegment; // the interval projected onto the epipolar line
  struct LineMatch;       // best match along the line

  //! Projects the interval onto the target's epipolar line; an end when it leaves the image or needs no search.
  std::optional<TraceEnd> projectInterval(const ImmaturePoint &pt, const TraceContext &context,
                                          EpipolarSegment &segment) const;
  //! Expected matching error along the line, pixels (DSO errorInPixel); an end when the search cannot improve.
  std::optional<TraceEnd> expectedPixelError(const ImmaturePoint &pt, const TraceContext &context,
                                             const EpipolarSegment &segment, float &errorInPixel) const;
  //! Discrete search of the pattern along the segment (\e numSteps positions); updates the point's quality.
  LineMatch searchAlongLine(ImmaturePoint &pt, const TraceContext &context, const EpipolarSegment &segment,
                            const std::array<float, kPatternSize> &reference, int &numSteps) const;
  //! Gauss-Newton refinement of the match along the line (one unknown: the position in steps).
  void refineAlongLine(const ImmaturePoint &pt, const TraceContext &context,
                       const std::array<float, kPatternSize> &reference, LineMatch &match) const;
  //! New inverse-depth interval from the refined match +- the expected error (or an outlier end).
  static TraceEnd updateInterval(ImmaturePoint &pt, const TraceContext &context, const EpipolarSegment &segment,
                                 const LineMatch &match, float errorInPixel);

  float m_huberThreshold;         //!< intensity units
  float m_gradientWeightCSq;      //!< c^2 of the gradient weight
  float m_outlierEnergyPerPixel;  //!< intensity^2
  float m_minImprovementFactor;   //!< see Mapper::traceMinImprovementFactor
  float m_slackInterval;          //!< pixels
  float m_stepSize;               //!< pixels
  int m_gaussNewtonIterations;    //!<
  float m_gaussNewtonThreshold;   //!< pixels (in units of the step)
  float m_extraSlackOnThreshold;  //!< factor
  float m_maxPixelSearchFraction; //!< of (width + height)
};
} // namespace hslam

#endif
