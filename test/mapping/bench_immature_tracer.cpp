// Cost of one epipolar trace (ImmaturePointTracer::trace) on the synthetic room at 640x480, about 2000 points on
// gradient pixels of frame 0:
//   FirstTrace   : infinite interval, the longest search (DSO maxPixSearch: 0.027 (w + h) = 30 px)
//   BoundedTrace : the interval from a first trace in frame 1, traced again in frame 3 (the usual case)
// "per_trace" is the time per traced point.
#include "map/Frame.h"
#include "map/ImmaturePoint.h"
#include "mapping/ImmaturePointTracer.h"
#include "math/ViSPConversions.h"

#include <visp3/hslam/vpHSlamParameters.h>
#include <visp3/hslam/vpHSlamSyntheticScene.h>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <memory>
#include <vector>

namespace
{
using hslam::Frame;
using hslam::FramePtr;
using hslam::ImmaturePoint;

constexpr unsigned int kWidth = 640, kHeight = 480;
constexpr float kMinGradientNorm = 15.f;
constexpr int kGridStep = 5;

struct Data {
  vpHSlamParameters params;
  FramePtr host, first, target;
  std::vector<ImmaturePoint> fresh;   //!< never traced
  std::vector<ImmaturePoint> bounded; //!< traced once, in frame 1
};

FramePtr makeFrame(const vpHSlamSyntheticScene &scene, unsigned int i)
{
  vpImage<unsigned char> I;
  scene.render(i, I);
  const vpCameraParameters cam = scene.getCameraParameters();
  FramePtr frame = std::make_shared<Frame>();
  frame->id = frame->keyframeId = static_cast<int>(i);
  frame->cMw = hslam::toSE3(scene.getPose(i).inverse());
  frame->pyramid.build(I, hslam::PinholeIntrinsics{cam.get_px(), cam.get_py(), cam.get_u0(), cam.get_v0()}, 5, 5000);
  return frame;
}

const Data &data()
{
  static const Data d = [] {
    Data out;
    vpHSlamSyntheticScene scene;
    scene.configure(kWidth, kHeight, 300, 30.0, 1);
    out.host = makeFrame(scene, 0);
    out.first = makeFrame(scene, 1);
    out.target = makeFrame(scene, 3);
    const hslam::ImmaturePointTracer tracer(out.params.mapper, out.params.tracker);
    const hslam::PyramidLevel &level0 = out.host->pyramid.level(0);
    for (int v = 8; v < level0.height - 8; v += kGridStep) {
      for (int u = 8; u < level0.width - 8; u += kGridStep) {
        ImmaturePoint pt;
        if (level0.gradSq[static_cast<size_t>(v * level0.width + u)] >= kMinGradientNorm * kMinGradientNorm &&
            tracer.createImmaturePoint(*out.host, static_cast<float>(u), static_cast<float>(v), 0, pt)) {
          out.fresh.push_back(pt);
        }
      }
    }
    out.bounded = out.fresh;
    tracer.traceAll(out.bounded, *out.host, *out.first);
    return out;
  }();
  return d;
}

void runTraces(benchmark::State &state, const std::vector<ImmaturePoint> &source)
{
  const Data &d = data();
  const hslam::ImmaturePointTracer tracer(d.params.mapper, d.params.tracker);
  std::vector<ImmaturePoint> points(source.size());
  int good = 0;
  for (auto _ : state) {
    std::copy(source.begin(), source.end(), points.begin());
    const hslam::TraceStatistics stats = tracer.traceAll(points, *d.host, *d.target);
    good = stats.good;
    benchmark::DoNotOptimize(points.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * static_cast<int64_t>(points.size()));
  state.counters["points"] = static_cast<double>(points.size());
  state.counters["good"] = static_cast<double>(good);
  state.counters["per_trace"] = benchmark::Counter(
      static_cast<double>(points.size()), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}

void FirstTrace(benchmark::State &state)
{
  runTraces(state, data().fresh);
}
void BoundedTrace(benchmark::State &state)
{
  runTraces(state, data().bounded);
}
} // namespace

BENCHMARK(FirstTrace)->Unit(benchmark::kMicrosecond);
BENCHMARK(BoundedTrace)->Unit(benchmark::kMicrosecond);
