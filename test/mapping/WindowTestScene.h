/*
 * H-SLAM for ViSP.
 */
/*!
  \file WindowTestScene.h
  \brief Keyframes with exact poses and exact point depths from vpHSlamSyntheticScene, for the window BA tests.
*/
#ifndef HSLAM_TEST_WINDOW_TEST_SCENE_H
#define HSLAM_TEST_WINDOW_TEST_SCENE_H

#include "map/Keyframe.h"
#include "mapping/PhotometricResidual.h"
#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <cmath>
#include <memory>
#include <random>
#include <vector>

namespace hslam_test
{
//! Points of a test keyframe are picked one per cell of this size (pixels), at the largest gradient.
constexpr int kCellSize = 14;
//! Minimum |grad I| for a test point, grey levels per pixel.
constexpr float kMinGradient = 8.f;
//! A point is kept only when the depth under every pattern pixel is within this fraction of the centre's:
//! the BA models the patch as fronto-parallel, so points on depth edges or steep planes would bias the tests.
constexpr double kMaxPatternDepthVariation = 0.01;

struct TestScene {
  vpHSlamSyntheticScene scene;
  hslam::PinholeIntrinsics K;
  vpHSlamParameters params;

  explicit TestScene(unsigned int width = 320, unsigned int height = 240, unsigned int frames = 120)
  {
    scene.configure(width, height, frames, 30.0, 3);
    const vpCameraParameters cam = scene.getCameraParameters();
    K.fx = cam.get_px();
    K.fy = cam.get_py();
    K.cx = cam.get_u0();
    K.cy = cam.get_v0();
  }

  hslam::SE3d trueCMw(unsigned int frame) const { return hslam::toSE3(scene.getPose(frame)).inverse(); }

  //! Keyframe of a sequence frame with its exact pose, a = b = 0, and up to \e maxPoints exact points.
  hslam::KeyframePtr makeKeyframe(unsigned int frame, int keyframeId, int maxPoints) const
  {
    auto f = std::make_shared<hslam::Frame>();
    f->id = static_cast<int>(frame);
    f->keyframeId = keyframeId;
    f->cMw = trueCMw(frame);
    scene.render(frame, f->raw);
    f->pyramid.build(f->raw, K, params.tracker.maxPyramidLevels, params.tracker.minCoarsestPixels);
    auto kf = std::make_shared<hslam::Keyframe>();
    kf->frame = f;
    addPoints(*kf, maxPoints);
    return kf;
  }

  void addPoints(hslam::Keyframe &kf, int maxPoints) const
  {
    const hslam::PyramidLevel &L = kf.frame->pyramid.level(0);
    const unsigned int frame = static_cast<unsigned int>(kf.frame->id);
    const int margin = hslam::kPatternPadding + 2;
    std::vector<std::pair<int, int>> picks;
    for (int cy = margin; cy + kCellSize < L.height - margin; cy += kCellSize) {
      for (int cx = margin; cx + kCellSize < L.width - margin; cx += kCellSize) {
        float best = kMinGradient * kMinGradient;
        int bu = -1, bv = -1;
        for (int v = cy; v < cy + kCellSize; ++v) {
          for (int u = cx; u < cx + kCellSize; ++u) {
            const float g = L.gradSq[static_cast<size_t>(v * L.width + u)];
            if (g > best) {
              best = g;
              bu = u;
              bv = v;
            }
          }
        }
        if (bu >= 0) {
          picks.emplace_back(bu, bv);
        }
      }
    }
    for (const auto &pk : picks) {
      if (static_cast<int>(kf.points.size()) >= maxPoints) {
        break;
      }
      const double d = scene.depthAt(pk.first, pk.second, frame);
      bool planar = d > 0.;
      for (int k = 0; k < hslam::kPatternSize && planar; ++k) {
        const double dk = scene.depthAt(pk.first + hslam::kPattern[k][0], pk.second + hslam::kPattern[k][1], frame);
        planar = std::fabs(dk - d) < kMaxPatternDepthVariation * d;
      }
      if (!planar) {
        continue;
      }
      hslam::MapPoint p;
      p.hostKeyframeId = kf.id();
      p.u = static_cast<float>(pk.first);
      p.v = static_cast<float>(pk.second);
      p.idepth = 1. / d;
      if (!hslam::samplePatch(L, p.u, p.v, params.tracker.gradientWeightC, p.patch, p.patchWeight)) {
        continue;
      }
      kf.points.push_back(p);
    }
  }
};

//! Rotation angle (degrees) and translation norm of the difference of two world-to-camera poses.
inline void poseError(const hslam::SE3d &a, const hslam::SE3d &b, double &rotDeg, double &trans)
{
  const hslam::SE3d d = a * b.inverse();
  rotDeg = d.log().tail<3>().norm() * 180. / M_PI;
  trans = d.translation().norm();
}
} // namespace hslam_test

#endif
