/*
 * H-SLAM for ViSP.
 */
#include "system/FramePreprocessor.h"

#include <visp3/hslam/vpHSlamException.h>

#include <atomic>
#include <cmath>
#include <sstream>

namespace hslam
{
namespace
{
//! Frames kept for reuse: the window's keyframes (up to 7 while a keyframe is made), the current and last frames,
//! and frames queued for the mapping thread; beyond, frames are allocated and freed as usual. Decision: with 4, every
//! frame that arrived while the pooled ones were held by keyframes had its pyramid (several MB) allocated and freed,
//! which fragmented the heap under the global map's small blocks (4000-frame soak at 640x480, vo-reuse: 9-22 MB of
//! free heap held, resident memory rising in steps, 0.13-0.18 MB per keyframe against 0.09 MB of heap in use); with
//! 12, 2 MB of free heap and resident memory rising 0.085 MB per keyframe (frames 1000-3500), tracking p95 the same
//! within the runs' spread (4.2-4.9 ms). The pool keeps only frames that were in use at the same time, so it never
//! holds more than the run's peak; after a reset its idle frames stay for the next segment (up to 12, about 84 MB at
//! 640x480, not counted in the statistics' window memory).
constexpr size_t kFramePoolSize = 12;
} // namespace

FramePreprocessor::FramePreprocessor(const vpHSlamCamera &camera, const vpHSlamPhotometricCalibration &photometric,
                                     bool usePhotometric, const vpHSlamParameters::Tracker &tracker)
    : m_rectifier(camera), m_photometric(photometric), m_usePhotometric(usePhotometric && !photometric.isEmpty()),
      m_levels(1), m_inputWidth(camera.getWidth()), m_inputHeight(camera.getHeight())
{
  const vpCameraParameters K = m_rectifier.getCameraParameters();
  m_K0.fx = K.get_px();
  m_K0.fy = K.get_py();
  m_K0.cx = K.get_u0();
  m_K0.cy = K.get_v0();
  m_maxLevels = tracker.maxPyramidLevels;
  m_minCoarsestPixels = tracker.minCoarsestPixels;
  m_levels = ImagePyramid::levelCount(width(), height(), m_maxLevels, m_minCoarsestPixels);
}

FramePtr FramePreprocessor::process(const vpImage<unsigned char> &I, double timestamp, double exposure, int id)
{
  if (I.getSize() == 0 || I.getWidth() != m_inputWidth || I.getHeight() != m_inputHeight) {
    std::ostringstream msg;
    msg << __FILE__ << ":" << __LINE__ << ": image " << id << " is " << I.getWidth() << "x" << I.getHeight()
        << " pixels, the camera calibration expects " << m_inputWidth << "x" << m_inputHeight;
    throw vpHSlamException(vpHSlamException::invalidImage, msg.str());
  }
  FramePtr frame;
  for (const FramePtr &pooled : m_pool) {
    if (pooled.use_count() == 1) { // only the pool holds it: no other thread can reach it
      // Pairs with the release of the mapping thread's last reference: its writes to the frame happen before ours.
      std::atomic_thread_fence(std::memory_order_acquire);
      frame = pooled;
      break;
    }
  }
  if (!frame) {
    frame = std::make_shared<Frame>();
    if (m_pool.size() < kFramePoolSize) {
      m_pool.push_back(frame);
    }
  }
  frame->keyframeId = -1;
  frame->cMw = SE3d();
  frame->affine = AffineBrightness();
  frame->id = id;
  frame->timestamp = timestamp;
  frame->exposure = (exposure > 0. && std::isfinite(exposure)) ? exposure : 1.;
  m_rectifier.rectify(I, frame->raw);
  if (m_usePhotometric) {
    // Exposure stays out of the irradiance (see the file comment): pass "unknown" so only G and V apply.
    m_photometric.toIrradiance(I, -1., m_irradianceInput);
    m_rectifier.rectify(m_irradianceInput, m_intensity);
    frame->pyramid.build(m_intensity, m_K0, m_maxLevels, m_minCoarsestPixels);
  } else {
    frame->pyramid.build(frame->raw, m_K0, m_maxLevels, m_minCoarsestPixels);
  }
  return frame;
}
} // namespace hslam
