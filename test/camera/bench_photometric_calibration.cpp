// Cost of the per-frame photometric correction (lookup table + precomputed 1/V) at common input sizes.
#include <visp3/hslam/vpHSlamPhotometricCalibration.h>

#include <benchmark/benchmark.h>

#include <vector>

namespace
{
vpHSlamPhotometricCalibration makeCalibration(unsigned int width, unsigned int height, bool withVignette)
{
  vpHSlamPhotometricCalibration calib;
  std::vector<double> G(256);
  for (int i = 0; i < 256; ++i) {
    G[i] = i + 0.002 * i * i; // any increasing curve
  }
  calib.setInverseResponse(G);
  if (withVignette) {
    vpImage<float> V(height, width);
    for (unsigned int v = 0; v < height; ++v) {
      for (unsigned int u = 0; u < width; ++u) {
        V[v][u] = 1.0f + 0.001f * ((u + v) % 500);
      }
    }
    calib.setVignette(V);
  }
  return calib;
}

void runToIrradiance(benchmark::State &state, bool withVignette)
{
  const unsigned int width = static_cast<unsigned int>(state.range(0));
  const unsigned int height = static_cast<unsigned int>(state.range(1));
  const vpHSlamPhotometricCalibration calib = makeCalibration(width, height, withVignette);
  vpImage<unsigned char> I(height, width);
  for (unsigned int k = 0; k < I.getSize(); ++k) {
    I.bitmap[k] = static_cast<unsigned char>(k * 31);
  }
  vpImage<float> B(height, width);
  for (auto _ : state) {
    calib.toIrradiance(I, 20.0, B);
    benchmark::DoNotOptimize(B.bitmap);
    benchmark::ClobberMemory();
  }
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(I.getSize()));
}

void BM_ToIrradianceResponseAndVignette(benchmark::State &state)
{
  runToIrradiance(state, true);
}
void BM_ToIrradianceResponseOnly(benchmark::State &state)
{
  runToIrradiance(state, false);
}
} // namespace

BENCHMARK(BM_ToIrradianceResponseAndVignette)->Args({640, 480})->Args({1280, 1024})->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_ToIrradianceResponseOnly)->Args({640, 480})->Args({1280, 1024})->Unit(benchmark::kMicrosecond);
