// Cost of the Lie-group primitives used per residual and per iteration (SE3/Sim3 exp, log, compose, act,
// Jacobians). Reference numbers for the tracker and the pose-graph optimiser.
#include "math/Sim3.h"

#include <benchmark/benchmark.h>

#include <random>

namespace
{
using Vector6d = Eigen::Matrix<double, 6, 1>;
using Vector7d = Eigen::Matrix<double, 7, 1>;

Vector6d sampleTwist()
{
  std::mt19937 rng(7u);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vector6d xi;
  for (int i = 0; i < 6; ++i) {
    xi(i) = u(rng);
  }
  return xi;
}

Vector7d sampleSim3Tangent()
{
  Vector7d xi;
  xi << sampleTwist(), 0.3;
  return xi;
}

void BM_SE3Exp(benchmark::State &state)
{
  const Vector6d xi = sampleTwist();
  for (auto _ : state) {
    benchmark::DoNotOptimize(hslam::SE3d::exp(xi));
  }
}
BENCHMARK(BM_SE3Exp);

void BM_SE3Log(benchmark::State &state)
{
  const hslam::SE3d T = hslam::SE3d::exp(sampleTwist());
  for (auto _ : state) {
    benchmark::DoNotOptimize(T.log());
  }
}
BENCHMARK(BM_SE3Log);

void BM_SE3ComposeAndAct(benchmark::State &state)
{
  const hslam::SE3d A = hslam::SE3d::exp(sampleTwist());
  const hslam::SE3d B = A.inverse();
  const Eigen::Vector3d p(0.1, -0.2, 2.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize((A * B) * p);
  }
}
BENCHMARK(BM_SE3ComposeAndAct);

void BM_SE3ActionJacobian(benchmark::State &state)
{
  const hslam::SE3d T = hslam::SE3d::exp(sampleTwist());
  const Eigen::Vector3d p(0.1, -0.2, 2.0);
  for (auto _ : state) {
    benchmark::DoNotOptimize(T.jacobianActionLeftPerturbation(p));
  }
}
BENCHMARK(BM_SE3ActionJacobian);

void BM_SE3JacobianLogRight(benchmark::State &state)
{
  const hslam::SE3d T = hslam::SE3d::exp(sampleTwist());
  for (auto _ : state) {
    benchmark::DoNotOptimize(T.jacobianLogRightPerturbation());
  }
}
BENCHMARK(BM_SE3JacobianLogRight);

void BM_Sim3Exp(benchmark::State &state)
{
  const Vector7d xi = sampleSim3Tangent();
  for (auto _ : state) {
    benchmark::DoNotOptimize(hslam::Sim3d::exp(xi));
  }
}
BENCHMARK(BM_Sim3Exp);

void BM_Sim3Log(benchmark::State &state)
{
  const hslam::Sim3d S = hslam::Sim3d::exp(sampleSim3Tangent());
  for (auto _ : state) {
    benchmark::DoNotOptimize(S.log());
  }
}
BENCHMARK(BM_Sim3Log);
} // namespace
