#include "map/MetricFrame.h"

#include "features/ImagePyramid.h"
#include "math/ViSPConversions.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <set>

namespace hslam
{

SE3d outputPose(const MetricFit &fit, const SE3d &wMc)
{
  if (!fit.metric) {
    return wMc;
  }
  return SE3d(fit.mSw.unitQuaternion() * wMc.unitQuaternion(), fit.mSw * wMc.translation());
}

bool appliesTo(const MetricFit &fit, unsigned int segment)
{
  return fit.metric && (fit.allSegments || fit.segment == segment);
}

Eigen::Vector3d outputPoint(const MetricFit &fit, const Eigen::Vector3d &pw)
{
  return fit.metric ? Eigen::Vector3d(fit.mSw * pw) : pw;
}

MapMetricFrame toMapMetricFrame(const MetricFit &fit)
{
  MapMetricFrame m;
  m.present = fit.metric;
  if (fit.metric) {
    m.tagFrame = fit.tagFrame;
    m.segment = static_cast<int>(fit.segment);
    m.oMw = SE3d(fit.mSw.unitQuaternion(), fit.mSw.translation());
    m.scale = fit.mSw.scale();
    m.scaleUncertainty = fit.scaleUncertainty;
  }
  return m;
}

MetricFit fromMapMetricFrame(const MapMetricFrame &frame)
{
  MetricFit fit;
  if (frame.present) {
    fit.metric = true;
    fit.allSegments = true; // localisation-only locates frames against any of the loaded keyframes
    fit.tagFrame = frame.tagFrame;
    fit.segment = static_cast<unsigned int>(frame.segment);
    fit.mSw = Sim3d(frame.oMw.unitQuaternion(), frame.oMw.translation(), frame.scale);
    fit.scale = frame.scale;
    fit.scaleUncertainty = frame.scaleUncertainty;
  }
  return fit;
}

MetricFrame::MetricFrame(const vpHSlamTag &tag, const vpHSlamParameters::TagFrame &options)
    : m_tag(tag), m_options(options)
{
}

void MetricFrame::setTag(const vpHSlamTag &tag, const vpHSlamParameters::TagFrame &options, const vpCameraParameters &K)
{
  std::lock_guard<std::mutex> detectorLock(m_detectorMutex);
  m_detector.reset(tag.isSet() ? new TagDetector(tag, K) : nullptr);
  std::lock_guard<std::mutex> lock(m_mutex);
  m_tag = tag;
  m_options = options;
  m_K = K;
  m_sightings.clear();
  m_fit = MetricFit();
  m_detectionMsTotal = 0.;
  m_detections = 0;
  ++m_generation;
}

vpHSlamTag MetricFrame::tag() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_tag;
}

void MetricFrame::observeKeyframe(int keyframeId, unsigned int segment, const vpImage<unsigned char> &image,
                                  const PoseLookup &keyframePose, const PointLookup &windowPoints)
{
  {
    std::lock_guard<std::mutex> detectorLock(m_detectorMutex);
    if (!m_detector) {
      return;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const std::vector<TagSighting> sightings = m_detector->detect(image);
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    addSightings(keyframeId, segment, sightings);
    std::lock_guard<std::mutex> lock(m_mutex);
    m_segment = segment;
    m_detectionMsTotal += ms;
    ++m_detections;
  }
  refit(keyframePose, windowPoints);
}

double MetricFrame::detectionMsMean() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_detections > 0 ? m_detectionMsTotal / m_detections : 0.;
}

vpHSlamTrajectory MetricFrame::toOutput(const vpHSlamTrajectory &trajectory,
                                        const std::vector<unsigned int> &segments) const
{
  const MetricFit fit = current();
  if (!fit.metric) {
    return trajectory;
  }
  vpHSlamTrajectory out;
  for (size_t i = 0; i < trajectory.size(); ++i) {
    const bool convert = i < segments.size() && appliesTo(fit, segments[i]);
    out.add(trajectory.getTimestamp(i),
            convert ? toVpHomogeneousMatrix(outputPose(fit, toSE3(trajectory.get_wMc(i)))) : trajectory.get_wMc(i));
  }
  return out;
}

void MetricFrame::startSegment(unsigned int segment)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_segment = segment;
  m_fit = MetricFit(); // also when a discarded segment's number is used again
  m_fit.segment = segment;
}

void MetricFrame::rescaleKeyframes(const std::vector<int> &ids, const std::vector<double> &scales)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  for (Stored &s : m_sightings) {
    for (size_t k = 0; k < ids.size() && k < scales.size(); ++k) {
      if (s.keyframeId == ids[k] && scales[k] > 0.) {
        s.depthScale *= scales[k]; // map units divided by the scale: a unit is that many times more metres
      }
    }
  }
}

void MetricFrame::addSightings(int keyframeId, unsigned int segment, const std::vector<TagSighting> &sightings)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  for (const TagSighting &s : sightings) {
    m_sightings.push_back(Stored{keyframeId, segment, s.id, s.cMt, s.corners, 0., 0});
  }
}

bool MetricFrame::measureDepthScale(const Stored &sighting, const SE3d &wMc, const vpCameraParameters &K,
                                    const std::vector<Eigen::Vector3d> &points, double &scale, int &count)
{
  const SE3d cMw = wMc.inverse();
  // The tag plane in the camera: normal n through the tag's centre c (metres).
  const Eigen::Vector3d n = sighting.cMt.rotationMatrix().col(2), c = sighting.cMt.translation();
  const double nc = n.dot(c);
  const PinholeIntrinsics pinhole{K.get_px(), K.get_py(), K.get_u0(), K.get_v0()};
  std::vector<double> ratios;
  for (const Eigen::Vector3d &pw : points) {
    const Eigen::Vector3d pc = cMw * pw;
    if (pc.z() <= 0.) {
      continue;
    }
    const Eigen::Vector2d uv = pinhole.project(pc);
    // Inside the (convex) quad: the same side of its four edges.
    int positive = 0, negative = 0;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector2d &a = sighting.corners[static_cast<size_t>(k)];
      const Eigen::Vector2d &b = sighting.corners[static_cast<size_t>((k + 1) % 4)];
      const double cross = (b - a).x() * (uv - a).y() - (b - a).y() * (uv - a).x();
      (cross >= 0. ? positive : negative) += 1;
    }
    if (positive != 4 && negative != 4) {
      continue;
    }
    const Eigen::Vector3d ray = pinhole.unproject(uv.x(), uv.y(), 1.); // z = 1: the depth along it is nc / nr
    const double nr = n.dot(ray);
    if (std::fabs(nr) < 1e-6) {
      continue;
    }
    const double metricDepth = nc / nr;
    if (metricDepth > 0.) {
      ratios.push_back(metricDepth / pc.z());
    }
  }
  count = static_cast<int>(ratios.size());
  if (count < kMinDepthPoints) {
    return false;
  }
  scale = upperMedian(ratios);
  return true;
}

void MetricFrame::refit(const PoseLookup &keyframePose, const PointLookup &windowPoints)
{
  std::vector<Stored> sightings;
  bool tagFrame = false;
  vpHSlamParameters::TagFrame options;
  vpCameraParameters K;
  unsigned int segment = 0, generation = 0;
  {
    std::lock_guard<std::mutex> lock(m_mutex);
    sightings = m_sightings;
    tagFrame = m_tag.hasId();
    options = m_options;
    K = m_K;
    segment = m_segment;
    generation = m_generation;
  }
  // The current segment's sightings: one fit per tag id, the best trusted.
  MetricFit best;
  best.segment = segment;
  if (!sightings.empty()) {
    std::vector<Eigen::Vector3d> points;
    if (windowPoints) {
      windowPoints(points);
    }
    std::map<int, std::vector<TagView>> byTag;
    std::vector<std::pair<size_t, std::pair<double, int>>> measured;
    for (size_t i = 0; i < sightings.size(); ++i) {
      Stored &s = sightings[i];
      SE3d wMc;
      if (s.segment != segment || !keyframePose(s.keyframeId, wMc)) {
        continue;
      }
      double scale = 0.;
      int count = 0;
      if (!points.empty() && measureDepthScale(s, wMc, K, points, scale, count)) {
        s.depthScale = scale;
        s.depthPoints = count;
        measured.push_back({i, {scale, count}});
      }
      TagView view{wMc, s.cMt};
      view.depthScale = s.depthScale;
      view.depthPoints = s.depthPoints;
      byTag[s.tagId].push_back(view);
    }
    bool first = true;
    for (const auto &entry : byTag) {
      const MetricFit fit = fitMetricFrame(entry.second, tagFrame, options);
      if (first || (fit.metric && !best.metric) ||
          (fit.metric == best.metric && fit.scaleUncertainty < best.scaleUncertainty)) {
        best = fit;
        best.segment = segment;
        first = false;
      }
    }
    std::lock_guard<std::mutex> lock(m_mutex);
    if (generation != m_generation) {
      return; // setTag() or clear() came meanwhile: this fit is of sightings that are gone
    }
    for (const auto &m : measured) {
      // The back end is the only writer of sightings (appended, never reordered), so the index still names it.
      if (m.first < m_sightings.size()) {
        m_sightings[m.first].depthScale = m.second.first;
        m_sightings[m.first].depthPoints = m.second.second;
      }
    }
  }
  std::lock_guard<std::mutex> lock(m_mutex);
  if (generation == m_generation) {
    m_fit = best;
  }
}

MetricFit MetricFrame::current() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return m_fit.metric || !m_loaded.metric ? m_fit : m_loaded;
}

void MetricFrame::setLoaded(const MetricFit &fit)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_loaded = fit;
}

unsigned int MetricFrame::sightingCount() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  return static_cast<unsigned int>(m_sightings.size());
}

std::vector<MetricFrame::SegmentSighting> MetricFrame::segmentSightings() const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  std::vector<SegmentSighting> out;
  for (const Stored &s : m_sightings) {
    if (s.segment == m_segment) {
      out.push_back({s.keyframeId, s.tagId, s.cMt});
    }
  }
  return out;
}

bool MetricFrame::seenAgain(int keyframeId) const
{
  std::lock_guard<std::mutex> lock(m_mutex);
  std::map<int, std::set<int>> keyframesByTag; // the segment's sighting keyframes of each tag seen by keyframeId
  for (const Stored &s : m_sightings) {
    if (s.segment == m_segment && s.keyframeId == keyframeId) {
      keyframesByTag[s.tagId];
    }
  }
  for (const Stored &s : m_sightings) {
    const auto it = keyframesByTag.find(s.tagId);
    if (it != keyframesByTag.end() && s.segment == m_segment && s.keyframeId < keyframeId) {
      it->second.insert(s.keyframeId);
    }
  }
  for (const auto &entry : keyframesByTag) {
    int run = 1, newer = keyframeId;
    bool before = false; // a visit before this run
    for (auto k = entry.second.rbegin(); k != entry.second.rend(); ++k) {
      if (newer - *k >= kRevisitKeyframes) {
        before = true;
        break;
      }
      ++run;
      newer = *k;
    }
    if (before && (run == 1 || run == 3)) {
      return true;
    }
  }
  return false;
}

void MetricFrame::clear()
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_sightings.clear();
  m_fit = MetricFit();
  m_loaded = MetricFit();
  m_segment = 0;
  m_detectionMsTotal = 0.;
  m_detections = 0;
  ++m_generation;
}
} // namespace hslam
