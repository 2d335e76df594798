/*
 * H-SLAM for ViSP.
 */
#include "system/RunStatistics.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <time.h>

namespace hslam
{
namespace
{
constexpr double kKiloBytesPerMegaByte = 1024.;
} // namespace

double percentile(std::vector<double> values, double q)
{
  if (values.empty()) {
    return 0.;
  }
  q = std::min(1., std::max(0., q));
  // Nearest rank: the smallest value with at least q of the values at or below it.
  size_t rank = static_cast<size_t>(std::ceil(q * static_cast<double>(values.size())));
  rank = std::max<size_t>(rank, 1) - 1;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(rank), values.end());
  return values[rank];
}

double processMemoryMb(const char *field)
{
  std::ifstream status("/proc/self/status");
  std::string line;
  const size_t n = std::strlen(field);
  while (std::getline(status, line)) {
    if (line.compare(0, n, field) == 0) {
      std::istringstream in(line.substr(n));
      double kb = 0.;
      if (in >> kb) {
        return kb / kKiloBytesPerMegaByte;
      }
    }
  }
  return 0.;
}

double nowMs()
{
  using Clock = std::chrono::steady_clock;
  return std::chrono::duration<double, std::milli>(Clock::now().time_since_epoch()).count();
}

double threadCpuMs()
{
  timespec ts{};
  if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0) {
    return 0.;
  }
  constexpr double kMsPerSecond = 1e3, kMsPerNanosecond = 1e-6;
  return static_cast<double>(ts.tv_sec) * kMsPerSecond + static_cast<double>(ts.tv_nsec) * kMsPerNanosecond;
}

void RunStatistics::addTrackingMs(double ms)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_trackingMs.push_back(ms);
}

void RunStatistics::addInitializationMs(double ms)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_initializationMs.push_back(ms);
}

void RunStatistics::addKeyframeMappingMs(double ms)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_keyframeMs.push_back(ms);
}

void RunStatistics::addFrameMappingMs(double ms)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_frameMappingMs.push_back(ms);
}

void RunStatistics::addPosedFrame(GeometricReason reason)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  ++m_posedFrames;
  m_geometricFrames += reason != GeometricReason::none ? 1 : 0;
  m_geometricLargeMotion += reason == GeometricReason::largeMotion ? 1 : 0;
  m_geometricPredictionRefused += reason == GeometricReason::predictionRefused ? 1 : 0;
  m_geometricDirectFailed += reason == GeometricReason::directFailed ? 1 : 0;
}

void RunStatistics::addHybridFrame(int matches, int inliers, double geometricWeight)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_orbMatches.push_back(matches);
  m_orbInliers.push_back(inliers);
  m_geometricWeight.push_back(geometricWeight);
}

void RunStatistics::addTrackingMsDuringLoopCorrection(double ms)
{
  std::lock_guard<std::mutex> lock(m_mutex);
  ++m_framesDuringLoopCorrection;
  m_trackingMsMaxDuringLoopCorrection = std::max(m_trackingMsMaxDuringLoopCorrection, ms);
}

RunStatistics::Summary RunStatistics::summary() const
{
  constexpr double kMedian = 0.5, kP95 = 0.95, kMax = 1.;
  std::lock_guard<std::mutex> lock(m_mutex);
  Summary s;
  s.trackingMsMedian = percentile(m_trackingMs, kMedian);
  s.trackingMsP95 = percentile(m_trackingMs, kP95);
  s.trackingMsMax = percentile(m_trackingMs, kMax);
  s.framesDuringLoopCorrection = m_framesDuringLoopCorrection;
  s.trackingMsMaxDuringLoopCorrection = m_trackingMsMaxDuringLoopCorrection;
  s.initializationMsMedian = percentile(m_initializationMs, kMedian);
  s.keyframeMsMedian = percentile(m_keyframeMs, kMedian);
  s.keyframeMsP95 = percentile(m_keyframeMs, kP95);
  s.frameMappingMsMedian = percentile(m_frameMappingMs, kMedian);
  s.orbMatchesMedian = percentile(m_orbMatches, kMedian);
  s.orbInliersMedian = percentile(m_orbInliers, kMedian);
  s.geometricWeightMedian = percentile(m_geometricWeight, kMedian);
  s.posedFrames = m_posedFrames;
  s.geometricFrames = m_geometricFrames;
  s.geometricLargeMotion = m_geometricLargeMotion;
  s.geometricPredictionRefused = m_geometricPredictionRefused;
  s.geometricDirectFailed = m_geometricDirectFailed;
  return s;
}

void RunStatistics::clear()
{
  std::lock_guard<std::mutex> lock(m_mutex);
  m_trackingMs.clear();
  m_initializationMs.clear();
  m_keyframeMs.clear();
  m_frameMappingMs.clear();
  m_orbMatches.clear();
  m_orbInliers.clear();
  m_posedFrames = m_geometricFrames = 0;
  m_geometricLargeMotion = m_geometricPredictionRefused = m_geometricDirectFailed = 0;
  m_geometricWeight.clear();
  m_framesDuringLoopCorrection = 0;
  m_trackingMsMaxDuringLoopCorrection = 0.;
}
} // namespace hslam
