/*
 * H-SLAM for ViSP.
 */
// Cost of one LM iteration of the window BA (7 keyframes, ~2000 active points, 640x480): linearisation of every
// residual, Schur complement, reduced solve, trial-step energy, re-linearisation after an accepted step.
#include "WindowTestScene.h"

#include "mapping/WindowOptimizer.h"

#include <benchmark/benchmark.h>

using namespace hslam;

namespace
{
constexpr int kKeyframes = 7;
constexpr unsigned int kFrameStep = 4;
constexpr int kPointsPerKeyframe = 2000 / kKeyframes + 1;

struct BenchWindow {
  hslam_test::TestScene scene{640, 480, 120};
  std::vector<KeyframePtr> kfs;
  std::vector<SE3d> start;
  BenchWindow()
  {
    for (int k = 0; k < kKeyframes; ++k) {
      kfs.push_back(scene.makeKeyframe(static_cast<unsigned int>(k) * kFrameStep, k, kPointsPerKeyframe));
      Eigen::Matrix<double, 6, 1> xi;
      xi << 0.003 * (k % 2), 0.002, -0.002 * (k % 3), 0.001, -0.0005 * k, 0.0005;
      if (k > 0) {
        kfs.back()->frame->cMw = SE3d::exp(xi) * kfs.back()->frame->cMw;
      }
      start.push_back(kfs.back()->frame->cMw);
    }
  }
  void reset()
  {
    for (size_t k = 0; k < kfs.size(); ++k) {
      kfs[k]->frame->cMw = start[k];
    }
  }
};

BenchWindow &window()
{
  static BenchWindow w;
  return w;
}

void BM_WindowOptimizerIteration(benchmark::State &state)
{
  BenchWindow &w = window();
  WindowOptimizer opt(w.scene.params);
  for (auto &kf : w.kfs) {
    opt.addKeyframe(kf);
  }
  double ms = 0.;
  int iterations = 0;
  OptimizationSummary s;
  for (auto _ : state) {
    state.PauseTiming();
    w.reset();
    state.ResumeTiming();
    s = opt.optimize(1);
    ms += s.totalMs;
    iterations += s.iterations;
  }
  state.counters["points"] = s.activePoints;
  state.counters["residuals"] = s.inlierResiduals;
  state.counters["ms_per_iteration"] = iterations > 0 ? ms / iterations : 0.;
}
BENCHMARK(BM_WindowOptimizerIteration)->Unit(benchmark::kMillisecond)->MinTime(2.0);
} // namespace
