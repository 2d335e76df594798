/*
 * H-SLAM for ViSP.
 */
/*!
  \file LocalMapperImpl.h
  \brief The state behind LocalMapper (private to system/: LocalMapper.cpp and LocalMapperRelocalization.cpp).
*/
#ifndef HSLAM_SYSTEM_LOCAL_MAPPER_IMPL_H
#define HSLAM_SYSTEM_LOCAL_MAPPER_IMPL_H

#include "features/SharedPointSelector.h"
#include "loop/GlobalBundleJob.h"
#include "mapping/ImmaturePointTracer.h"
#include "mapping/PointActivation.h"
#include "mapping/WindowOptimizer.h"
#include "system/LocalMapper.h"
#include "tracking/CoarseTracker.h"
#include "tracking/RelocalizationIndex.h"

#include <map>
#include <memory>
#include <vector>

namespace hslam
{
//! Image width at which pixel thresholds are given (globalMap.reuseRadiusPx, mapper.rotationFlowPx); other widths
//! scale them.
constexpr double kReferenceWidthPx = 640.;

struct LocalMapper::Impl {
  Impl(const vpHSlamParameters &p, const PinholeIntrinsics &K, int w, int h, bool calibrated, const OrbVocabulary *voc)
      : params(p), K0(K), width(w), height(h), tracer(p.mapper, p.tracker), activation(p.mapper),
        selector(p.features, p.tracking.mode != vpHSlamParameters::trackingDirect ||
                                 p.system.mode != vpHSlamParameters::modeVoStrict),
        optimizer(p)
  {
    optimizer.setPhotometricallyCalibrated(calibrated);
    vocabulary = voc;
    if (vocabulary) {
      relocalization = std::make_unique<RelocalizationIndex>(*vocabulary);
    }
  }

  vpHSlamParameters params;
  PinholeIntrinsics K0;
  int width, height;
  ImmaturePointTracer tracer;
  PointActivation activation;
  SharedPointSelector selector;
  WindowOptimizer optimizer;
  std::vector<SelectedPixel> selected;     //!< scratch of the pixel selection
  std::vector<bool> selectedCorner;        //!< per selected pixel: a FAST corner
  std::vector<cv::Point2f> describePixels; //!< scratch of describe()
  std::vector<OrbDescriptor> describeOut;
  std::vector<bool> describeValid;
  std::vector<float> describeAngles;

  //! Descriptor sharing: ORB descriptors for points [begin, end) of \e points, hosted by \e frame.
  void describe(const Frame &frame, std::vector<ImmaturePoint> &points, size_t begin)
  {
    if (!selector.withDescriptors() || begin >= points.size()) {
      return;
    }
    describePixels.clear();
    for (size_t i = begin; i < points.size(); ++i) {
      describePixels.emplace_back(points[i].u, points[i].v);
    }
    selector.describe(frame.raw, describePixels, describeOut, describeValid, describeAngles);
    for (size_t i = begin; i < points.size(); ++i) {
      const size_t k = i - begin;
      points[i].hasOrb = describeValid[k];
      points[i].orb = describeOut[k];
      points[i].orbAngleDeg = describeAngles[k];
    }
  }
  std::vector<CoarseTrackerPoint> referencePoints;     //!< tracking reference of the newest keyframe
  std::vector<ReferenceFeature> referenceFeatures;     //!< its points with descriptors (hybrid tracking)
  std::unique_ptr<RelocalizationIndex> relocalization; //!< null without a vocabulary
  const OrbVocabulary *vocabulary;
  int referenceKeyframe = -1;
  std::vector<KeyframeState> marginalizedStates; //!< keyframes that left since the last report
  int keyframesInSegment = 0;
  //! A relocalisation confirmed against the map took place in this segment: its initialisation is not checked any
  //! more (see LocalMapper::noteRelocalization()).
  bool relocalizedInSegment = false;
  double initNoiseSigma = 0.; //!< image noise of the segment's first keyframe (estimateNoiseSigma), intensity units
  std::map<int, std::vector<PairInformation>> pendingPairs; //!< pose-pose links of the keyframes being marginalised
  //! Real time: the global bundle adjustment's thread (cancelled with this state: clear(), reset(), destruction).
  BackgroundBundleAdjustment globalBa;
};
} // namespace hslam

#endif
